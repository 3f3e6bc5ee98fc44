#include "rgbdtam/runtime/key_value.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "rgbdtam/core/assert.hpp"
#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/core/text_lines.hpp"

namespace rgbdtam {
namespace {
constexpr int kMaxKeys = 256;
constexpr size_t kMaxLine = 512;

const KeySpec* find_key(const KeyTable& table, const char* key) {
  for (int i = 0; i < table.count; ++i)
    if (std::strcmp(table.specs[i].key, key) == 0) return &table.specs[i];
  return nullptr;
}

// Trims leading/trailing blanks in place; returns the trimmed start.
char* trim(char* s) {
  while (*s == ' ' || *s == '\t') ++s;
  char* end = s + std::strlen(s);
  while (end > s && (end[-1] == ' ' || end[-1] == '\t' || end[-1] == '\r')) *--end = '\0';
  return s;
}

Status assign(const KeySpec& spec, const char* value, const char* where, void* target) {
  // An empty text is a value ("none"); an empty number is not.
  if (*value == '\0' && spec.type != ValueType::kText) {
    return Status::error(StatusCode::kInvalidArgument, "%s: key '%s' has no value", where,
                         spec.key);
  }
  void* field = spec.field(target);
  switch (spec.type) {
    case ValueType::kCustom:
      if (!spec.parse(value, field)) {
        return Status::error(StatusCode::kInvalidArgument, "%s: key '%s': '%s' is not valid (%s)",
                             where, spec.key, value, spec.doc);
      }
      return Status::ok();
    case ValueType::kText:
      if (std::strlen(value) >= static_cast<size_t>(kTextBytes)) {
        return Status::error(StatusCode::kInvalidArgument,
                             "%s: key '%s': value longer than %d characters", where, spec.key,
                             kTextBytes - 1);
      }
      std::strcpy(static_cast<char*>(field), value);
      return Status::ok();
    case ValueType::kBool:
      if (std::strcmp(value, "true") == 0 || std::strcmp(value, "1") == 0) {
        *static_cast<bool*>(field) = true;
      } else if (std::strcmp(value, "false") == 0 || std::strcmp(value, "0") == 0) {
        *static_cast<bool*>(field) = false;
      } else {
        return Status::error(StatusCode::kInvalidArgument, "%s: key '%s': '%s' is not true/false",
                             where, spec.key, value);
      }
      return Status::ok();
    default:
      break;
  }
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(value, &end);
  if (end == value || *trim(end) != '\0' || errno != 0 || !std::isfinite(v)) {
    return Status::error(StatusCode::kInvalidArgument, "%s: key '%s': '%s' is not a number", where,
                         spec.key, value);
  }
  if (v < spec.min || v > spec.max) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: key '%s': %s is out of range [%g, %g] %s", where, spec.key, value,
                         spec.min, spec.max, spec.unit);
  }
  switch (spec.type) {
    case ValueType::kReal:
      *static_cast<double*>(field) = v;
      break;
    case ValueType::kFloat:
      *static_cast<float*>(field) = static_cast<float>(v);
      break;
    case ValueType::kInt:
      if (v != std::floor(v)) {
        return Status::error(StatusCode::kInvalidArgument,
                             "%s: key '%s': '%s' is not a whole number", where, spec.key, value);
      }
      *static_cast<int*>(field) = static_cast<int>(v);
      break;
    case ValueType::kMillisecondsAsNs:
      *static_cast<int64_t*>(field) = static_cast<int64_t>(std::llround(v * 1e6));
      break;
    case ValueType::kDegreesAsRadians:
      *static_cast<double*>(field) = v * M_PI / 180.0;
      break;
    default:
      break;
  }
  return Status::ok();
}

Status apply_line(char* line, const char* where, const KeyTable& table, void* target, bool* seen) {
  // Text only: a binary file is named, never echoed to the terminal.
  for (const char* c = line; *c != '\0'; ++c) {
    const unsigned char b = static_cast<unsigned char>(*c);
    if ((b < 0x20 && b != '\t') || b == 0x7f) {
      return Status::error(StatusCode::kInvalidArgument,
                           "%s: not text (control byte 0x%02x at column %d)", where, b,
                           static_cast<int>(c - line) + 1);
    }
  }
  char* hash = std::strchr(line, '#');
  if (hash != nullptr) *hash = '\0';
  char* s = trim(line);
  if (*s == '\0') return Status::ok();
  char* eq = std::strchr(s, '=');
  if (eq == nullptr) {
    return Status::error(StatusCode::kInvalidArgument, "%s: expected 'key = value', got '%s'",
                         where, s);
  }
  *eq = '\0';
  const char* key = trim(s);
  const char* value = trim(eq + 1);
  const KeySpec* spec = find_key(table, key);
  if (spec == nullptr) {
    return Status::error(StatusCode::kInvalidArgument, "%s: unknown key '%s'", where, key);
  }
  if (seen != nullptr) {
    // In a file a second value is a mistake (which one was meant?); --set exists to override.
    if (seen[spec - table.specs]) {
      return Status::error(StatusCode::kInvalidArgument, "%s: key '%s' is given a second time",
                           where, key);
    }
    seen[spec - table.specs] = true;
  }
  return assign(*spec, value, where, target);
}
}  // namespace

Status parse_key_values(const char* text, const char* source, const KeyTable& table, void* target) {
  RGBDTAM_ASSERT(table.count <= kMaxKeys, "schema larger than kMaxKeys");
  bool seen[kMaxKeys] = {false};
  char line[kMaxLine];
  int line_no = 0;
  for (const char* cursor = text; cursor != nullptr && *cursor != '\0';) {
    size_t len = 0;
    const char* next = split_line(cursor, &len);
    ++line_no;
    char where[300];
    std::snprintf(where, sizeof(where), "%s:%d", source, line_no);
    // A comment may be any length; only what comes before it must fit.
    const void* hash = std::memchr(cursor, '#', len);
    if (hash != nullptr) len = static_cast<size_t>(static_cast<const char*>(hash) - cursor);
    if (len >= sizeof(line)) {
      return Status::error(StatusCode::kInvalidArgument, "%s: line longer than %zu characters",
                           where, sizeof(line) - 1);
    }
    std::memcpy(line, cursor, len);
    line[len] = '\0';
    RGBDTAM_RETURN_IF_ERROR(apply_line(line, where, table, target, seen));
    cursor = next;
  }
  for (int i = 0; i < table.count; ++i) {
    if (table.specs[i].required && !seen[i]) {
      return Status::error(StatusCode::kInvalidArgument, "%s: missing required key '%s' (%s)",
                           source, table.specs[i].key, table.specs[i].doc);
    }
  }
  return Status::ok();
}

Status apply_key_value(const char* assignment, const char* source, const KeyTable& table,
                       void* target) {
  char line[kMaxLine];
  if (std::strlen(assignment) >= sizeof(line)) {
    return Status::error(StatusCode::kInvalidArgument, "%s: override too long", source);
  }
  std::strcpy(line, assignment);
  return apply_line(line, source, table, target, nullptr);
}

namespace {
// A number's range as the file writes it; empty for the other types.
void print_range(const KeySpec& s, char* out, size_t size) {
  const bool number = s.type == ValueType::kReal || s.type == ValueType::kFloat ||
                      s.type == ValueType::kInt || s.type == ValueType::kMillisecondsAsNs ||
                      s.type == ValueType::kDegreesAsRadians;
  if (number) {
    std::snprintf(out, size, "%g to %g", s.min, s.max);
  } else {
    std::snprintf(out, size, "%s", s.type == ValueType::kBool ? "true, false" : "");
  }
}
}  // namespace

void print_key_values(const KeyTable& table, void* target, char* buf, int size,
                      KeyListing listing) {
  int used = 0;
  if (listing == KeyListing::kMarkdown) {
    used = std::snprintf(buf, static_cast<size_t>(size),
                         "| key | value | unit | range | meaning |\n|---|---|---|---|---|\n");
  }
  for (int i = 0; i < table.count; ++i) {
    const KeySpec& s = table.specs[i];
    char value[kTextBytes];
    const void* f = s.field(target);
    switch (s.type) {
      case ValueType::kCustom:
        s.print(f, value, sizeof(value));
        break;
      case ValueType::kText:
        std::snprintf(value, sizeof(value), "%s", static_cast<const char*>(f));
        break;
      case ValueType::kBool:
        std::snprintf(value, sizeof(value), "%s", *static_cast<const bool*>(f) ? "true" : "false");
        break;
      case ValueType::kInt:
        std::snprintf(value, sizeof(value), "%d", *static_cast<const int*>(f));
        break;
      case ValueType::kMillisecondsAsNs:
        std::snprintf(value, sizeof(value), "%.15g",
                      static_cast<double>(*static_cast<const int64_t*>(f)) * 1e-6);
        break;
      case ValueType::kReal:
        std::snprintf(value, sizeof(value), "%.9g", *static_cast<const double*>(f));
        break;
      case ValueType::kDegreesAsRadians:
        std::snprintf(value, sizeof(value), "%.9g", *static_cast<const double*>(f) * 180.0 / M_PI);
        break;
      case ValueType::kFloat:
        std::snprintf(value, sizeof(value), "%g",
                      static_cast<double>(*static_cast<const float*>(f)));
        break;
    }
    if (used >= size) return;
    if (listing == KeyListing::kMarkdown) {
      char range[64];
      print_range(s, range, sizeof(range));
      used += std::snprintf(buf + used, static_cast<size_t>(size - used),
                            "| `%s` | %s | %s | %s | %s%s |\n", s.key, value, s.unit, range, s.doc,
                            s.required ? " (required)" : "");
    } else {
      used += std::snprintf(buf + used, static_cast<size_t>(size - used), "%s = %s  # %s%s%s\n",
                            s.key, value, s.doc, *s.unit != '\0' ? ", " : "", s.unit);
    }
  }
}

bool parse_pose_value(const char* value, void* field) {
  // A camera is mounted on its vehicle, a depth camera beside its colour camera: an offset of
  // kilometres is a typo that would put every pose sent that far off (1e300 reached the link
  // as inf).
  constexpr double kMaxOffsetM = 10.0;
  double v[7];
  int used = 0;
  if (std::sscanf(value, "%lf %lf %lf %lf %lf %lf %lf%n", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                  &v[6], &used) != 7 ||
      value[used] != '\0') {
    return false;
  }
  for (const double x : v) {
    if (!std::isfinite(x)) return false;  // NaN passes every comparison below unnoticed
  }
  const Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
  if (std::abs(q.norm() - 1.0) > 1e-3) return false;  // a typo, not a rotation
  for (int i = 4; i < 7; ++i) {
    if (std::abs(v[i]) > kMaxOffsetM) return false;
  }
  *static_cast<SE3*>(field) = SE3(q, Vector3d(v[4], v[5], v[6]));
  return true;
}

void print_pose_value(const void* field, char* out, size_t size) {
  const SE3& T = *static_cast<const SE3*>(field);
  const Eigen::Quaterniond& q = T.quaternion();
  std::snprintf(out, size, "%.6g %.6g %.6g %.6g %.6g %.6g %.6g", q.w(), q.x(), q.y(), q.z(),
                T.translation().x(), T.translation().y(), T.translation().z());
}

}  // namespace rgbdtam

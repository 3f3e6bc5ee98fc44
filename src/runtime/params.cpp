#include "rgbdtam/runtime/params.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace rgbdtam {
namespace {

enum class ParamType { kReal, kFloat, kInt, kBool, kMillisecondsAsNs, kResiduals };

struct ParamSpec {
  const char* key;
  ParamType type;
  double min, max;
  const char* unit;
  const char* doc;
  void* (*field)(Params&);
  bool required;
};

#define RGBDTAM_FIELD(expr) [](Params& p) -> void* { return &p.expr; }

// The schema. Keys are stable: a removed key keeps its line as a comment.
const ParamSpec kSpecs[] = {
    {"camera.width", ParamType::kInt, 8, 4096, "px", "image width, divisible by 8",
     RGBDTAM_FIELD(camera.width_px), true},
    {"camera.height", ParamType::kInt, 8, 4096, "px", "image height, divisible by 8",
     RGBDTAM_FIELD(camera.height_px), true},
    {"camera.fx", ParamType::kReal, 1, 1e5, "px", "focal length x", RGBDTAM_FIELD(camera.fx_px),
     true},
    {"camera.fy", ParamType::kReal, 1, 1e5, "px", "focal length y", RGBDTAM_FIELD(camera.fy_px),
     true},
    {"camera.cx", ParamType::kReal, -1e4, 1e4, "px", "principal point x",
     RGBDTAM_FIELD(camera.cx_px), true},
    {"camera.cy", ParamType::kReal, -1e4, 1e4, "px", "principal point y",
     RGBDTAM_FIELD(camera.cy_px), true},
    {"camera.k1", ParamType::kReal, -10, 10, "", "radial distortion k1",
     RGBDTAM_FIELD(distortion.k1), false},
    {"camera.k2", ParamType::kReal, -10, 10, "", "radial distortion k2",
     RGBDTAM_FIELD(distortion.k2), false},
    {"camera.p1", ParamType::kReal, -1, 1, "", "tangential distortion p1",
     RGBDTAM_FIELD(distortion.p1), false},
    {"camera.p2", ParamType::kReal, -1, 1, "", "tangential distortion p2",
     RGBDTAM_FIELD(distortion.p2), false},
    {"camera.k3", ParamType::kReal, -10, 10, "", "radial distortion k3",
     RGBDTAM_FIELD(distortion.k3), false},
    {"depth.factor", ParamType::kReal, 1e-3, 1e6, "1/m", "raw depth units per metre",
     RGBDTAM_FIELD(sensor.depth_factor), true},
    {"depth.min", ParamType::kReal, 0.0, 100, "m", "nearest valid sensor depth",
     RGBDTAM_FIELD(sensor.depth_range.min_m), false},
    {"depth.max", ParamType::kReal, 0.1, 100, "m", "farthest valid sensor depth",
     RGBDTAM_FIELD(sensor.depth_range.max_m), false},
    {"depth.baseline", ParamType::kReal, 1e-3, 10, "m", "projector-camera baseline b",
     RGBDTAM_FIELD(sensor.baseline_m), false},
    {"depth.focal", ParamType::kReal, 1, 1e5, "px", "IR camera focal length f",
     RGBDTAM_FIELD(sensor.depth_focal_px), false},
    {"depth.disparity_sigma", ParamType::kReal, 1e-4, 10, "px", "disparity noise sigma_d",
     RGBDTAM_FIELD(sensor.disparity_sigma_px), false},
    {"depth.max_rgb_dt_ms", ParamType::kMillisecondsAsNs, 0, 1000, "ms",
     "largest colour-depth time difference", RGBDTAM_FIELD(sensor.max_rgb_depth_dt_ns), false},
    {"depth.time_offset_ms", ParamType::kMillisecondsAsNs, -100, 100, "ms",
     "pair colour at t with the depth stamped nearest t + offset",
     RGBDTAM_FIELD(sensor.depth_time_offset_ns), false},
    {"tracker.residuals", ParamType::kResiduals, 0, 0, "",
     "PS, PD, GIDS, GIDD, GIDD*, PS+GIDD, PS+GDD, ...", RGBDTAM_FIELD(tracker.residuals), false},
    {"tracker.photometric_points", ParamType::kInt, 10, 1e6, "",
     "photometric points at the finest level (x1/3 per level)",
     RGBDTAM_FIELD(tracker.photometric_points_finest), false},
    {"tracker.gradient_top_fraction", ParamType::kFloat, 0.01, 1, "",
     "fraction of strongest gradients eligible as points",
     RGBDTAM_FIELD(tracker.gradient_top_fraction), false},
    {"tracker.canny_low", ParamType::kFloat, 1, 2000, "grey/px",
     "Canny low threshold (Sobel-3 magnitude)", RGBDTAM_FIELD(tracker.canny_low), false},
    {"tracker.canny_high", ParamType::kFloat, 1, 2000, "grey/px", "Canny high threshold",
     RGBDTAM_FIELD(tracker.canny_high), false},
    {"tracker.iterations_l0", ParamType::kInt, 0, 100, "", "Gauss-Newton iterations at 640x480",
     RGBDTAM_FIELD(tracker.max_iterations[0]), false},
    {"tracker.iterations_l1", ParamType::kInt, 0, 100, "", "Gauss-Newton iterations at 320x240",
     RGBDTAM_FIELD(tracker.max_iterations[1]), false},
    {"tracker.iterations_l2", ParamType::kInt, 0, 100, "", "Gauss-Newton iterations at 160x120",
     RGBDTAM_FIELD(tracker.max_iterations[2]), false},
    {"tracker.iterations_l3", ParamType::kInt, 0, 100, "", "Gauss-Newton iterations at 80x60",
     RGBDTAM_FIELD(tracker.max_iterations[3]), false},
    {"tracker.min_relative_decrease", ParamType::kReal, 0, 1, "",
     "stop a level below this relative cost decrease", RGBDTAM_FIELD(tracker.min_relative_decrease),
     false},
    {"tracker.robust_c", ParamType::kReal, 0.1, 100, "sigma", "Geman-McClure scale",
     RGBDTAM_FIELD(tracker.robust_c), false},
    {"tracker.geometric_weight", ParamType::kReal, 0, 1000, "",
     "lambda on the normalised geometric error", RGBDTAM_FIELD(tracker.geometric_weight), false},
    {"tracker.keyframe_overlap", ParamType::kReal, 0, 1, "", "new keyframe below this overlap",
     RGBDTAM_FIELD(tracker.keyframe_overlap), false},
    {"tracker.gain_brightness", ParamType::kBool, 0, 1, "", "estimate gain and brightness",
     RGBDTAM_FIELD(tracker.gain_brightness), false},
    {"tracker.motion_model", ParamType::kBool, 0, 1, "", "constant-velocity initial guess",
     RGBDTAM_FIELD(tracker.motion_model), false},
    {"map.keyframe_pool", ParamType::kInt, 3, 4096, "",
     "keyframes kept; when full the oldest non-reference one is recycled",
     RGBDTAM_FIELD(keyframe_pool_size), false},
    {"map.reuse_candidates", ParamType::kInt, 0, 16, "",
     "nearest earlier keyframes tried before creating a new one (0: no map reuse)",
     RGBDTAM_FIELD(reuse_candidates), false},
    {"map.enabled", ParamType::kBool, 0, 1, "", "multi-view mapping of each new keyframe",
     RGBDTAM_FIELD(map_enabled), false},
    {"map.threaded", ParamType::kBool, 0, 1, "",
     "run the mapper on its own thread (else synchronously, deterministic)",
     RGBDTAM_FIELD(map_threaded), false},
    {"map.queue_frames", ParamType::kInt, 1, 64, "",
     "tracker-to-mapper queue slots; a full queue drops the frame", RGBDTAM_FIELD(map_queue_frames),
     false},
    {"map.frames_per_keyframe", ParamType::kInt, 1, 100, "", "frames triangulated per keyframe",
     RGBDTAM_FIELD(map_frames_per_keyframe), false},
    {"map.min_baseline_ratio", ParamType::kReal, 0, 1, "",
     "spacing of triangulated frames, relative to the median depth",
     RGBDTAM_FIELD(map_min_baseline_ratio), false},
    {"map.seeds", ParamType::kInt, 100, 100000, "", "edge pixels mapped per keyframe",
     RGBDTAM_FIELD(map_seeds), false},
    {"tracker.lost_frames_before_reset", ParamType::kInt, 1, 100000, "frames",
     "consecutive lost frames before a new keyframe restarts tracking",
     RGBDTAM_FIELD(lost_frames_before_reset), false},
};
#undef RGBDTAM_FIELD

constexpr int kSpecCount = sizeof(kSpecs) / sizeof(kSpecs[0]);

const ParamSpec* find_spec(const char* key) {
  for (const ParamSpec& s : kSpecs)
    if (std::strcmp(s.key, key) == 0) return &s;
  return nullptr;
}

// Trims leading/trailing blanks in place; returns the trimmed start.
char* trim(char* s) {
  while (*s == ' ' || *s == '\t') ++s;
  char* end = s + std::strlen(s);
  while (end > s && (end[-1] == ' ' || end[-1] == '\t' || end[-1] == '\r')) *--end = '\0';
  return s;
}

Status assign(const ParamSpec& spec, const char* value, const char* where, Params* p) {
  if (*value == '\0') {
    return Status::error(StatusCode::kInvalidArgument, "%s: key '%s' has no value", where,
                         spec.key);
  }
  void* field = spec.field(*p);
  if (spec.type == ParamType::kResiduals) {
    if (!ResidualConfig::parse(value, static_cast<ResidualConfig*>(field))) {
      return Status::error(StatusCode::kInvalidArgument,
                           "%s: key '%s': '%s' is not a residual configuration (%s)", where,
                           spec.key, value, spec.doc);
    }
    return Status::ok();
  }
  if (spec.type == ParamType::kBool) {
    bool b;
    if (std::strcmp(value, "true") == 0 || std::strcmp(value, "1") == 0) {
      b = true;
    } else if (std::strcmp(value, "false") == 0 || std::strcmp(value, "0") == 0) {
      b = false;
    } else {
      return Status::error(StatusCode::kInvalidArgument, "%s: key '%s': '%s' is not true/false",
                           where, spec.key, value);
    }
    *static_cast<bool*>(field) = b;
    return Status::ok();
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
    case ParamType::kReal:
      *static_cast<double*>(field) = v;
      break;
    case ParamType::kFloat:
      *static_cast<float*>(field) = static_cast<float>(v);
      break;
    case ParamType::kInt:
      if (v != std::floor(v)) {
        return Status::error(StatusCode::kInvalidArgument,
                             "%s: key '%s': '%s' is not a whole number", where, spec.key, value);
      }
      *static_cast<int*>(field) = static_cast<int>(v);
      break;
    case ParamType::kMillisecondsAsNs:
      *static_cast<int64_t*>(field) = static_cast<int64_t>(std::llround(v * 1e6));
      break;
    default:
      break;
  }
  return Status::ok();
}

Status apply_line(char* line, const char* where, Params* p, bool* seen) {
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
  const ParamSpec* spec = find_spec(key);
  if (spec == nullptr) {
    return Status::error(StatusCode::kInvalidArgument, "%s: unknown key '%s'", where, key);
  }
  if (seen != nullptr) seen[spec - kSpecs] = true;
  return assign(*spec, value, where, p);
}

Status check_consistency(const char* source, const Params& p) {
  if (p.camera.width_px % 8 != 0 || p.camera.height_px % 8 != 0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: keys 'camera.width'/'camera.height' must be divisible by 8 "
                         "for the 4-level pyramid (got %dx%d)",
                         source, p.camera.width_px, p.camera.height_px);
  }
  if (p.sensor.depth_range.min_m >= p.sensor.depth_range.max_m) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: key 'depth.min' (%g) must be below 'depth.max' (%g)", source,
                         p.sensor.depth_range.min_m, p.sensor.depth_range.max_m);
  }
  // The reference, three keyframes being mapped, one per queue slot, and a free one.
  const int pool_needed = p.map_queue_frames + 5;
  if (p.map_enabled && p.keyframe_pool_size < pool_needed) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: key 'map.keyframe_pool' (%d) must be at least map.queue_frames + 5 "
                         "(%d) when mapping is enabled",
                         source, p.keyframe_pool_size, pool_needed);
  }
  if (p.tracker.canny_low > p.tracker.canny_high) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: key 'tracker.canny_low' must not exceed 'tracker.canny_high'",
                         source);
  }
  return Status::ok();
}
}  // namespace

Status parse_params(const char* text, const char* source, Params* out) {
  Params p = *out;
  bool seen[kSpecCount] = {false};
  char line[512];
  int line_no = 0;
  const char* cursor = text;
  while (*cursor != '\0') {
    const char* nl = std::strchr(cursor, '\n');
    const size_t len = nl != nullptr ? static_cast<size_t>(nl - cursor) : std::strlen(cursor);
    ++line_no;
    char where[300];
    std::snprintf(where, sizeof(where), "%s:%d", source, line_no);
    if (len >= sizeof(line)) {
      return Status::error(StatusCode::kInvalidArgument, "%s: line too long", where);
    }
    std::memcpy(line, cursor, len);
    line[len] = '\0';
    RGBDTAM_RETURN_IF_ERROR(apply_line(line, where, &p, seen));
    cursor += len + (nl != nullptr ? 1 : 0);
  }
  for (int i = 0; i < kSpecCount; ++i) {
    if (kSpecs[i].required && !seen[i]) {
      return Status::error(StatusCode::kInvalidArgument, "%s: missing required key '%s' (%s)",
                           source, kSpecs[i].key, kSpecs[i].doc);
    }
  }
  RGBDTAM_RETURN_IF_ERROR(check_consistency(source, p));
  *out = p;
  return Status::ok();
}

Status set_param(const char* assignment, const char* source, Params* out) {
  char line[512];
  if (std::strlen(assignment) >= sizeof(line)) {
    return Status::error(StatusCode::kInvalidArgument, "%s: override too long", source);
  }
  std::strcpy(line, assignment);
  Params p = *out;
  RGBDTAM_RETURN_IF_ERROR(apply_line(line, source, &p, nullptr));
  RGBDTAM_RETURN_IF_ERROR(check_consistency(source, p));
  *out = p;
  return Status::ok();
}

void print_params(const Params& in, char* buf, int size) {
  Params p = in;
  int used = 0;
  for (const ParamSpec& s : kSpecs) {
    char value[64];
    void* f = s.field(p);
    switch (s.type) {
      case ParamType::kResiduals:
        static_cast<ResidualConfig*>(f)->name(value, sizeof(value));
        break;
      case ParamType::kBool:
        std::snprintf(value, sizeof(value), "%s", *static_cast<bool*>(f) ? "true" : "false");
        break;
      case ParamType::kInt:
        std::snprintf(value, sizeof(value), "%d", *static_cast<int*>(f));
        break;
      case ParamType::kMillisecondsAsNs:
        std::snprintf(value, sizeof(value), "%.6f",
                      static_cast<double>(*static_cast<int64_t*>(f)) * 1e-6);
        break;
      case ParamType::kReal:
        std::snprintf(value, sizeof(value), "%.9g", *static_cast<double*>(f));
        break;
      case ParamType::kFloat:
        std::snprintf(value, sizeof(value), "%g", static_cast<double>(*static_cast<float*>(f)));
        break;
    }
    if (used >= size) return;
    used += std::snprintf(buf + used, static_cast<size_t>(size - used), "%s = %s  # %s%s%s\n",
                          s.key, value, s.doc, *s.unit != '\0' ? ", " : "", s.unit);
  }
}

}  // namespace rgbdtam

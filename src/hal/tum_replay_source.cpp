#include "rgbdtam/hal/tum_replay_source.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "rgbdtam/core/text_lines.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/tum_timestamp.hpp"

namespace rgbdtam {
namespace {
constexpr size_t kMaxListBytes = 64u << 20;
constexpr int kMaxListEntries = 1'000'000;

const char* skip_blanks(const char* s) {
  while (*s == ' ' || *s == '\t' || *s == ',') ++s;
  return s;
}
}  // namespace

Status parse_tum_list(const char* text, const char* source, TumList* out) {
  // Entries for the lines that hold something: a file of blank lines asks for nothing.
  int lines = 0;
  for (const char* line = text; line != nullptr && *line != '\0';) {
    size_t length = 0;
    const char* next = split_line(line, &length);
    const char* s = skip_blanks(line);
    lines += s < line + length && *s != '#' ? 1 : 0;
    line = next;
  }
  if (lines > kMaxListEntries) {
    return Status::error(StatusCode::kOutOfRange,
                         "%s: %d entries, more than the %d (over 9 hours at 30 Hz) a list may hold",
                         source, lines, kMaxListEntries);
  }
  out->entries.reset(new TumListEntry[static_cast<size_t>(std::max(lines, 1))]);
  out->size = 0;
  out->bad_lines = 0;
  int line_no = 0;
  for (const char* line = text; line != nullptr && *line != '\0';) {
    size_t length = 0;
    const char* next = split_line(line, &length);
    const char* end = line + length;
    ++line_no;
    const char* s = skip_blanks(line);
    if (s < end && *s != '#') {
      TumListEntry& e = out->entries[out->size];
      const char* after = parse_seconds_ns(s, &e.timestamp_ns);
      const char* name = after != nullptr ? skip_blanks(after) : nullptr;
      const char* name_end = name;
      while (name_end != nullptr && name_end < end && *name_end != ' ' && *name_end != '\t' &&
             *name_end != '\r' && *name_end != ',') {
        ++name_end;
      }
      const size_t len = name != nullptr ? static_cast<size_t>(name_end - name) : 0;
      const bool in_range =
          after == nullptr || (e.timestamp_ns >= 0 && e.timestamp_ns < kMaxStampNs);
      if (after == nullptr || (*after != ' ' && *after != '\t' && *after != ',') || len == 0 ||
          len >= sizeof(e.path) || !in_range) {
        if (out->bad_lines++ == 0) {
          out->first_problem =
              in_range ? Status::error(StatusCode::kCorrupt, "%s:%d: expected 'timestamp filename'",
                                       source, line_no)
                       : Status::error(StatusCode::kCorrupt,
                                       "%s:%d: timestamp out of range (0 to 4e9 s, 1970-2096)",
                                       source, line_no);
        }
      } else {
        std::memcpy(e.path, name, len);
        e.path[len] = '\0';
        ++out->size;
      }
    }
    line = next;
  }
  std::stable_sort(
      out->entries.get(), out->entries.get() + out->size,
      [](const TumListEntry& a, const TumListEntry& b) { return a.timestamp_ns < b.timestamp_ns; });
  // Two images at one instant: the first listed is kept, the others are reported.
  int kept = 0;
  for (int i = 0; i < out->size; ++i) {
    if (kept > 0 && out->entries[i].timestamp_ns == out->entries[kept - 1].timestamp_ns) {
      if (out->bad_lines++ == 0) {
        char stamp[32];
        format_seconds(out->entries[i].timestamp_ns, stamp, sizeof(stamp));
        out->first_problem = Status::error(StatusCode::kCorrupt,
                                           "%s: timestamp %s listed again (%s), the first kept",
                                           source, stamp, out->entries[i].path);
      }
      continue;
    }
    out->entries[kept++] = out->entries[i];
  }
  out->size = kept;
  if (out->size == 0) {
    return Status::error(StatusCode::kCorrupt, "%s: no 'timestamp filename' entries", source);
  }
  return Status::ok();
}

Status TumReplaySource::open(const char* folder, const SensorImageSize& size,
                             int64_t max_rgb_depth_dt_ns, int64_t depth_time_offset_ns) {
  if (std::strlen(folder) >= sizeof(folder_) - 200) {
    return Status::error(StatusCode::kInvalidArgument, "sequence path too long: %s", folder);
  }
  std::snprintf(folder_, sizeof(folder_), "%s", folder);
  size_ = size;
  for (int which = 0; which < 2; ++which) {
    char path[768];
    std::snprintf(path, sizeof(path), "%s/%s", folder_, which == 0 ? "rgb.txt" : "depth.txt");
    char* text = nullptr;
    RGBDTAM_RETURN_IF_ERROR(read_text_file(path, kMaxListBytes, &text));
    const Status s = parse_tum_list(text, path, which == 0 ? &rgb_ : &depth_);
    delete[] text;
    RGBDTAM_RETURN_IF_ERROR(s);
  }
  // Nearest depth for each colour frame (both lists are sorted).
  depth_match_.reset(new int[static_cast<size_t>(rgb_.size)]);
  int j = 0;
  for (int i = 0; i < rgb_.size; ++i) {
    const int64_t t = rgb_.entries[i].timestamp_ns + depth_time_offset_ns;
    while (j + 1 < depth_.size && std::llabs(depth_.entries[j + 1].timestamp_ns - t) <=
                                      std::llabs(depth_.entries[j].timestamp_ns - t)) {
      ++j;
    }
    const bool close = std::llabs(depth_.entries[j].timestamp_ns - t) < max_rgb_depth_dt_ns;
    depth_match_[i] = close ? j : -1;
  }
  // A PNG is at most its raw size plus zlib's and the chunks' overhead.
  file_capacity_ = std::max(size.pixels(), size.depth_pixels()) * 4 + (1u << 16);
  file_buf_.reset(new uint8_t[file_capacity_]);
  png_.allocate(std::max(size.width_px, size.depth_width_px));
  gray_.allocate(size.width_px, size.height_px);
  depth_img_.allocate(size.depth_width_px, size.depth_height_px);
  cursor_ = 0;
  return Status::ok();
}

Status TumReplaySource::load(const TumListEntry& e, bool depth, void* out) {
  char path[768];
  std::snprintf(path, sizeof(path), "%s/%s", folder_, e.path);
  size_t size = 0;
  RGBDTAM_RETURN_IF_ERROR(read_file(path, file_buf_.get(), file_capacity_, &size));
  const Status s = depth ? png_.decode_gray16(file_buf_.get(), size, size_.depth_width_px,
                                              size_.depth_height_px, static_cast<uint16_t*>(out))
                         : png_.decode_gray8(file_buf_.get(), size, size_.width_px, size_.height_px,
                                             static_cast<uint8_t*>(out));
  if (!s.is_ok()) return Status::error(s.code(), "%s: %s", path, s.message());
  return Status::ok();
}

Status TumReplaySource::depth_at(int index, ImageU16* depth) {
  RGBDTAM_ASSERT(index >= 0 && index < depth_.size, "depth_at: index outside depth.txt");
  return load(depth_.entries[index], true, depth->data());
}

Status TumReplaySource::next(SensorFrame* frame, Status* warning) {
  return next_into(&gray_, &depth_img_, frame, warning);
}

Status TumReplaySource::next_into(ImageU8* gray, ImageU16* depth, SensorFrame* frame,
                                  Status* warning) {
  *warning = Status::ok();
  if (cursor_ >= rgb_.size) return Status::error(StatusCode::kEndOfStream, "end of sequence");
  const int i = cursor_++;
  const TumListEntry& rgb = rgb_.entries[i];
  const Status s = load(rgb, false, gray->data());
  if (!s.is_ok()) {
    ++counters_.skipped;
    return s;
  }
  frame->sequence = static_cast<uint32_t>(i);
  frame->timestamp_ns = rgb.timestamp_ns;
  frame->gray = gray->data();
  frame->width_px = size_.width_px;
  frame->height_px = size_.height_px;
  frame->depth_width_px = size_.depth_width_px;
  frame->depth_height_px = size_.depth_height_px;
  frame->depth = nullptr;
  frame->depth_timestamp_ns = 0;
  const int d = depth_match_[i];
  if (d < 0) {
    *warning = Status::error(StatusCode::kNotFound, "%s/%s: no depth frame within the limit",
                             folder_, rgb.path);
  } else {
    const Status ds = load(depth_.entries[d], true, depth->data());
    if (ds.is_ok()) {
      frame->depth = depth->data();
      frame->depth_timestamp_ns = depth_.entries[d].timestamp_ns;
    } else {
      *warning = ds;
    }
  }
  if (frame->depth == nullptr) ++counters_.without_depth;
  ++counters_.delivered;
  return Status::ok();
}

}  // namespace rgbdtam

#pragma once
// Replays a TUM RGB-D folder (rgb.txt, depth.txt, PNGs) as a sensor source. Colour and depth
// are paired by nearest timestamp within the configured limit. A bad list line, a missing
// or corrupt image is reported and skipped; a frame whose depth is missing or corrupt is
// delivered without depth.

#include <memory>

#include "rgbdtam/core/image.hpp"
#include "rgbdtam/hal/png_decoder.hpp"
#include "rgbdtam/port/sensor_source.hpp"

namespace rgbdtam {

struct TumListEntry {
  int64_t timestamp_ns;
  char path[160];  // relative to the sequence folder
};

struct TumList {
  std::unique_ptr<TumListEntry[]> entries;
  int size = 0;
  int bad_lines = 0;
  Status first_problem;  // the first bad line, for the report
};

// Parses an rgb.txt/depth.txt-style list from text (init time).
Status parse_tum_list(const char* text, const char* source, TumList* out);

struct ReplayCounters {
  uint32_t delivered = 0;
  uint32_t skipped = 0;        // colour image missing or corrupt
  uint32_t without_depth = 0;  // no depth within the time limit, or depth unreadable
};

class TumReplaySource : public SensorSource {
 public:
  Status open(const char* folder, const SensorImageSize& size, int64_t max_rgb_depth_dt_ns,
              int64_t depth_time_offset_ns);
  Status next(SensorFrame* frame, Status* warning) override;
  // The same, decoding into the caller's images (of the sizes opened) instead of the source's own.
  Status next_into(ImageU8* gray, ImageU16* depth, SensorFrame* frame, Status* warning);

  int frame_count() const { return rgb_.size; }
  const SensorImageSize& size() const { return size_; }
  // The index of the frame next() delivers, and a jump forward to a later one.
  int position() const { return cursor_; }
  void skip_to(int index) { cursor_ = index > cursor_ ? index : cursor_; }
  const TumList& rgb_list() const { return rgb_; }
  const TumList& depth_list() const { return depth_; }
  // Depth image `index` of depth.txt, paired with a colour frame or not, into depth (of the
  // size opened): for tools that rewrite every depth image whatever the pairing.
  Status depth_at(int index, ImageU16* depth);
  const ReplayCounters& counters() const { return counters_; }
  size_t png_arena_high_water() const { return png_.arena_high_water(); }

 private:
  Status load(const TumListEntry& e, bool depth, void* out);

  char folder_[512] = {0};
  TumList rgb_, depth_;
  std::unique_ptr<int[]> depth_match_;  // per colour frame, index into depth_ or -1
  int cursor_ = 0;
  SensorImageSize size_;
  PngDecoder png_;
  std::unique_ptr<uint8_t[]> file_buf_;
  size_t file_capacity_ = 0;
  ImageU8 gray_;
  ImageU16 depth_img_;
  ReplayCounters counters_;
};

}  // namespace rgbdtam

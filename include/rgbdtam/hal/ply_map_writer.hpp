#pragma once
// Streams every keyframe's map into one binary PLY, as the paper's Figure 1 shows it: each
// keyframe's edge points back-projected with its own pose, not fused, coloured by intensity.
// The vertex count is patched into the header when the file is closed, which renames it into
// place (hal/file.hpp OutputFile); each keyframe's points are flushed as they come.

#include <cstdio>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/port/map_sink.hpp"

namespace rgbdtam {

class PlyMapWriter : public MapSink {
 public:
  ~PlyMapWriter() override;
  Status open(const char* path);
  void on_keyframe_map(int64_t timestamp_ns, const SE3& T_w_k, const PinholeIntrinsics& k,
                       const FixedVector<FusedPixel>& pixels) override;
  Status close();
  uint64_t points() const { return points_; }
  // The first write failure, naming the file and the reason.
  const Status& status() const { return file_.status(); }

 private:
  OutputFile file_;
  long count_offset_ = 0;
  uint64_t points_ = 0;
  char buffer_[1 << 16];
};

}  // namespace rgbdtam

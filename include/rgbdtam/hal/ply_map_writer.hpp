#pragma once
// Streams every keyframe's map into one binary PLY, as the paper's Figure 1 shows it: each
// keyframe's edge points back-projected with its own pose, not fused, coloured by intensity.
// The vertex count is patched into the header when the file is closed.

#include <cstdio>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/runtime/mapping.hpp"

namespace rgbdtam {

class PlyMapWriter : public MapSink {
 public:
  ~PlyMapWriter() override;
  Status open(const char* path);
  void on_keyframe_map(int64_t timestamp_ns, const SE3& T_w_k, const PinholeIntrinsics& k,
                       const FixedVector<FusedPixel>& pixels) override;
  Status close();
  uint64_t points() const { return points_; }

 private:
  std::FILE* file_ = nullptr;
  long count_offset_ = 0;
  uint64_t points_ = 0;
  bool write_failed_ = false;
  char buffer_[1 << 16];
};

}  // namespace rgbdtam

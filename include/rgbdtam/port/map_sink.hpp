#pragma once
// Where each finished keyframe map goes (the mapping module calls it; hal's PLY writer is one).

#include <cstdint>

#include "rgbdtam/core/camera.hpp"
#include "rgbdtam/core/fixed_vector.hpp"
#include "rgbdtam/core/multiview.hpp"
#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

// Receives each finished keyframe map, e.g. to export it. Called on the mapper's thread.
class MapSink {
 public:
  virtual ~MapSink() = default;
  virtual void on_keyframe_map(int64_t timestamp_ns, const SE3& T_w_k, const PinholeIntrinsics& k,
                               const FixedVector<FusedPixel>& pixels) = 0;
};

}  // namespace rgbdtam

#pragma once
// Canny edge detector: 3x3 Sobel, L2 magnitude, non-maximum suppression, hysteresis.
// Thresholds are Sobel magnitudes in 8-bit grey levels, as with OpenCV's aperture 3.

#include "rgbdtam/core/image.hpp"

namespace rgbdtam {

class CannyDetector {
 public:
  void allocate(int width, int height);
  // Writes 1 on edge pixels and 0 elsewhere; returns the edge count.
  int detect(const ImageF& gray_unit, float low, float high, ImageU8* edges);

 private:
  ImageF magnitude_;
  ImageU8 sector_;  // quantised gradient direction: 0 = horizontal .. 3
  std::unique_ptr<int32_t[]> stack_;
};

}  // namespace rgbdtam

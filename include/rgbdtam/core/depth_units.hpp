#pragma once
// Whether a structured-light sensor's depth is read in the right units. Such a sensor measures
// disparity in sub-pixel steps (PrimeSense: 1/8 px), so the depths it can report are a ladder
// whose rungs are evenly spaced in inverse depth, q / (f b). Read at the configured depth.factor,
// the spacing between a frame's distinct depth values is that only when the units are right: a
// units mistake (1000 raw units per metre for data made at 5000) scales every depth, and so
// every rung's spacing in inverse depth, by the same factor. The depth's own content (the scene,
// the motion) does not enter: only which values occur. fr1_xyz reads 1.003, fr3_teddy 1.019;
// fr1_xyz at depth.factor 1000, 0.201.
// A rendered plane makes a ladder of its own (its inverse depth is linear in the pixel's row),
// but one that moves with the camera: the sensor's rungs are fixed, and 97-100 % of a frame's
// values were in the frame before on fr1_xyz and fr3_teddy (2-3 % of the raw values in their
// span occur at all), where a renderer's recur by chance, as often as they are dense. A frame is
// read only when it is another depth frame than the last and most of its values recur.
// No allocation: one bit per raw value.

#include <cstdint>

namespace rgbdtam {

struct DepthUnitsReading {
  // Enough distinct values, spaced wider than the raw resolution, evenly and at the same
  // values as in the frame before (a renderer's or a time-of-flight sensor's depth has no
  // ladder: nothing to read).
  bool conclusive = false;
  double step_ratio = 0.0;      // the median spacing over the model's: 1 when the units are right
  double fitting_factor = 0.0;  // the depth.factor at which it would be 1
};

class DepthUnitsReader {
 public:
  // depth: raw values (0 = none); inverse_depth_step: q / (f b) of the configured sensor, 1/m.
  // Frames are compared with the one read before.
  DepthUnitsReading read(const uint16_t* depth, int pixels, double depth_factor,
                         double inverse_depth_step);

 private:
  static constexpr int kRawValues = 65536;
  uint64_t seen_[kRawValues / 64] = {};
  uint64_t seen_before_[kRawValues / 64] = {};
  uint64_t fingerprint_before_ = 0;
};

}  // namespace rgbdtam

#pragma once
// A rolling shutter exposes an image's rows one after another. A frame's pose is its middle
// row's; row y was exposed from T_c_row = exp(s * row_motion), s = y / (h - 1) - 1/2 readouts
// from the middle, where row_motion is the camera's twist over one readout (FramePyramid). Over
// a few milliseconds the motion is small, so points move between the two cameras to first order.

#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

struct RowMotion {
  float v[3], w[3];  // the twist over one readout: translation (m) and rotation (rad)
  float inverse_last_row;

  RowMotion(const Vector6d& row_motion, int height_px) {
    for (int i = 0; i < 3; ++i) {
      v[i] = static_cast<float>(row_motion[i]);
      w[i] = static_cast<float>(row_motion[3 + i]);
    }
    inverse_last_row = 1.f / static_cast<float>(height_px - 1);
  }
  // Readouts from the middle row to row y (sub-pixel rows too).
  float from_middle(float y) const { return y * inverse_last_row - 0.5f; }
  // p + s (w x p + v): a point of row s's camera into the middle row's (s), or of the middle
  // row's into row s's (-s).
  void move(float s, float* x, float* y, float* z) const {
    const float mx = w[1] * *z - w[2] * *y + v[0];
    const float my = w[2] * *x - w[0] * *z + v[1];
    const float mz = w[0] * *y - w[1] * *x + v[2];
    *x += s * mx;
    *y += s * my;
    *z += s * mz;
  }
};

}  // namespace rgbdtam

#pragma once
// A rolling shutter exposes an image's rows one after another. A frame's pose is its middle
// row's; row y was exposed from T_c_row = exp(s * row_motion), s = y / (h - 1) - 1/2 readouts
// from the middle, where row_motion is the camera's twist over one readout (FramePyramid). Over
// a few milliseconds the motion is small, so points move between the two cameras to first order.

#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

// Each image's twist over its readout (FramePyramid::fixed_row_motions).
struct RowMotions {
  Vector6d colour = Vector6d::Zero();
  Vector6d depth = Vector6d::Zero();
};

// The rows' motion a pose implies: the camera moved on from the last frame's at a constant
// velocity, so over a readout it moved by the motion between the two poses times the readout
// over the time between them. Tracking places the rows by the motion of the pose it has reached,
// where a velocity measured a frame earlier lags behind an accelerating camera.
struct PoseRowMotion {
  SE3 T_last_w;                // the last frame's camera, from the world
  double colour_fraction = 0;  // the colour image's readout over the time since that frame
  double depth_fraction = 0;   // ... the depth image's

  RowMotions at(const SE3& T_w_c) const {
    const Vector6d motion = (T_last_w * T_w_c).log();
    return {motion * colour_fraction, motion * depth_fraction};
  }
};

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

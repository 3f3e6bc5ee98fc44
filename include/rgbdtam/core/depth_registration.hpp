#pragma once
// Depth moved from the camera that measured it into another camera: a depth camera's image
// into the colour camera (registration, for sensors that do not register it themselves, as
// RealSense and Orbbec over plain UVC), or the reverse (the stress tool's virtual depth cameras).
//
// Each source pixel is a small square of surface at its depth: its centre is moved into the
// target and every target pixel whose centre falls within the square's bound there takes it, so
// a target with the finer pixels has no cracks; the square is 15 % wider than it would be facing
// the cameras, so that a slanted surface, stretched from one view to the other, has none either.
// Where several surfaces land on one pixel the nearest wins (a z-buffer); target pixels that no
// source pixel reaches (seen by the target but hidden from the source, or outside it) stay holes
// (0). Both images are raw: distorted pixels, depth in the same units; the target's depth is along
// its own optical axis.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "rgbdtam/core/camera.hpp"
#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

struct CameraModel {
  PinholeIntrinsics intrinsics;  // its image size included
  RadTanDistortion distortion;
};

class DepthRegistration {
 public:
  // Init time: a ray per source pixel, turned into the target's frame, and its square's size.
  // T_target_source: the target camera's frame from the source camera's.
  void init(const CameraModel& source, const CameraModel& target, const SE3& T_target_source,
            double depth_factor);
  // source: source.intrinsics' size; out: the target's size. Never allocates.
  void apply(const uint16_t* source, uint16_t* out);
  // What init allocates for a source of this size.
  static size_t bytes_needed(int source_width, int source_height) {
    return sizeof(float) * 5 * static_cast<size_t>(source_width) * source_height +
           sizeof(int32_t) * 5 * static_cast<size_t>(source_width);
  }

 private:
  // The row's pixels at their depths moved into the target: the target pixels each covers
  // ([x0_, x1_) x [y0_, y1_), empty for a pixel without depth) and its raw depth there.
  void move_row(const uint16_t* depth, int y);

  CameraModel target_;
  int source_width_ = 0, source_height_ = 0;
  float inverse_factor_ = 0, factor_ = 0;
  float t_[3] = {};
  // Per source pixel: its ray turned into the target's frame (z = 1 before turning), and the
  // half width and height of its square in the target's pixels.
  std::unique_ptr<float[]> ray_x_, ray_y_, ray_z_, half_width_, half_height_;
  std::unique_ptr<int32_t[]> x0_, x1_, y0_, y1_, raw_;  // one row's
};

}  // namespace rgbdtam

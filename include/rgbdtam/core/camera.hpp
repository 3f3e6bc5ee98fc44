#pragma once
// Pinhole camera with radial-tangential (Brown-Conrady, OpenCV order k1 k2 p1 p2 k3) distortion.
// Frame convention: x right, y down, z forward (OpenCV). Undistorted images keep the same
// intrinsics as the raw camera.

#include <cstdint>

#include "rgbdtam/core/image.hpp"

namespace rgbdtam {

// The pinhole projection, written once: a point (x, y, z) of a camera's frame, z > 0, to its
// pixel (u, v), and a pixel at depth z back to the point. Float, for the per-point loops.
struct Pinhole {
  float fx, fy, cx, cy;
  void project(float x, float y, float z, float* u, float* v) const {
    *u = fx * x / z + cx;
    *v = fy * y / z + cy;
  }
  // The same with 1/z given: one division per point instead of two, for the tracker's loops.
  void project_inverse_depth(float x, float y, float inverse_z, float* u, float* v) const {
    *u = fx * x * inverse_z + cx;
    *v = fy * y * inverse_z + cy;
  }
  void back_project(float u, float v, float z, float* x, float* y) const {
    *x = (u - cx) / fx * z;
    *y = (v - cy) / fy * z;
  }
};

struct PinholeIntrinsics {
  double fx_px = 0.0;
  double fy_px = 0.0;
  double cx_px = 0.0;
  double cy_px = 0.0;
  int width_px = 0;
  int height_px = 0;

  Pinhole pinhole() const {
    return {static_cast<float>(fx_px), static_cast<float>(fy_px), static_cast<float>(cx_px),
            static_cast<float>(cy_px)};
  }
  // Intrinsics of the next-coarser level of a 2x2-averaging pyramid: pixel centres
  // move by half a pixel, so c' = (c - 0.5) / 2.
  PinholeIntrinsics half() const {
    return {fx_px * 0.5,         fy_px * 0.5,  (cx_px - 0.5) * 0.5,
            (cy_px - 0.5) * 0.5, width_px / 2, height_px / 2};
  }
};

struct RadTanDistortion {
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;
  bool is_zero() const { return k1 == 0.0 && k2 == 0.0 && p1 == 0.0 && p2 == 0.0 && k3 == 0.0; }
  // Normalised undistorted -> normalised distorted coordinates.
  void distort(double x, double y, double* xd, double* yd) const;
  // Inverse of distort() by fixed-point iteration; exact to ~1e-10 for camera-sized fields.
  void undistort(double xd, double yd, double* x, double* y) const;
};

// Lookup tables from undistorted to raw pixels, built once at init.
class Undistorter {
 public:
  void init(const PinholeIntrinsics& k, const RadTanDistortion& d);
  bool is_identity() const { return identity_; }
  // Bilinear for intensities; pixels whose source lies outside the raw image become 0.
  void undistort_gray(const uint8_t* raw, ImageF* out_unit) const;
  // Nearest-neighbour for depth, so no depth is invented across discontinuities; each raw value
  // is mapped through `table` (65536 entries) on the way.
  void undistort_depth(const uint16_t* raw, const float* table, ImageF* out) const;

 private:
  static constexpr int kTapOne = 1 << 14;  // fixed-point 1 of the bilinear weights
  // Per output pixel: its top-left source pixel (0 with zero weights when outside) and the
  // weights of the top-left, top-right, bottom-left and bottom-right pixels.
  std::unique_ptr<int32_t[]> tap_index_;
  std::unique_ptr<uint16_t[]> tap_weight_[4];
  std::unique_ptr<int32_t[]> nearest_;
  int width_ = 0, height_ = 0;
  bool identity_ = true;
};

}  // namespace rgbdtam

#pragma once
// Per-frame image and inverse-depth pyramids. Level 0 is the finest (full resolution);
// each coarser level halves both sizes by 2x2 averaging (640x480 -> 80x60 over 4 levels).

#include "rgbdtam/core/camera.hpp"
#include "rgbdtam/core/rolling_shutter.hpp"
#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

constexpr int kPyramidLevels = 4;

struct DepthRange {
  double min_m = 0.3;
  double max_m = 5.0;
};

class FramePyramid {
 public:
  // Init time: the images, and the raw-depth -> inverse-depth table of the sensor.
  void allocate(const PinholeIntrinsics& finest, double depth_factor, const DepthRange& range);

  // gray[0] must already hold the undistorted [0,1] image; this builds the coarser levels.
  void build_gray();
  // Converts raw depth (units of 1/depth_factor m) to inverse depth, undistorting it on the way,
  // and builds the coarser levels. A pixel outside the range is invalid (0).
  void build_inverse_depth(const uint16_t* raw, const Undistorter& undistorter);
  // The same for depth that needs no undistortion (synthetic images).
  void build_inverse_depth(const ImageU16& undistorted);
  void clear_depth();
  // For a map other than the sensor's: write level 0 here, then build the coarser levels.
  ImageF& inverse_depth_level0() { return inv_depth_[0]; }
  void build_inverse_depth_levels();

  const PinholeIntrinsics& intrinsics(int level) const { return k_[level]; }
  ImageF& gray(int level) { return gray_[level]; }
  const ImageF& gray(int level) const { return gray_[level]; }
  const ImageF& inverse_depth(int level) const { return inv_depth_[level]; }
  bool has_depth() const { return has_depth_; }
  // Where the camera was when its depth image was taken, in the colour image's frame: identity
  // when both were taken together. A sensor that streams them unsynchronised (a Kinect: 8.5 ms
  // apart on average in fr1 after pairing) sees the depth from a camera that has moved on.
  void set_T_c_d(const SE3& T_c_d) { T_c_d_ = T_c_d; }
  const SE3& T_c_d() const { return T_c_d_; }
  // A rolling shutter: the camera's motion (twist) from the colour image's first row to its
  // last; row y was exposed from T_c_row(y) = exp((y / (h - 1) - 1/2) * row_motion), the
  // middle row at the image's pose. Zero for a global shutter or an unknown motion.
  void set_row_motion(const Vector6d& twist) { rows_.colour = twist; }
  // The same for the depth image's rows, from its middle row's camera (T_c_d).
  void set_depth_row_motion(const Vector6d& twist) { rows_.depth = twist; }
  // While the frame is tracked on from the last frame, the pose each pyramid level starts from
  // implies the rows' motions (PoseRowMotion, Tracker) in place of the two above, until
  // set_rows_fixed().
  void set_rows_follow_pose(const PoseRowMotion& m) {
    pose_rows_ = m;
    rows_follow_pose_ = true;
  }
  void set_rows_fixed() { rows_follow_pose_ = false; }
  // The rows' motions of the frame at T_w_c.
  RowMotions row_motions_at(const SE3& T_w_c) const {
    return rows_follow_pose_ ? pose_rows_.at(T_w_c) : rows_;
  }
  const RowMotions& fixed_row_motions() const { return rows_; }  // as set above

 private:
  PinholeIntrinsics k_[kPyramidLevels];
  ImageF gray_[kPyramidLevels];
  ImageF inv_depth_[kPyramidLevels];         // 1/m; 0 = no measurement
  std::unique_ptr<float[]> inverse_of_raw_;  // 65536 entries, 0 outside the valid range
  bool has_depth_ = false;
  SE3 T_c_d_;
  RowMotions rows_;
  PoseRowMotion pose_rows_;
  bool rows_follow_pose_ = false;
};

// Inverse depth changing by more than this fraction of itself per pixel is an occluding edge
// (or noise), not a surface seen by the sensor.
constexpr float kMaxRelativeDepthSlope = 0.1f;

// Valid inverse-depth pixels on a grid of `stride` px, and those of them on a surface: their
// four neighbours valid and both central differences within kMaxRelativeDepthSlope.
struct SurfaceCount {
  int valid = 0, on_surface = 0;
};
SurfaceCount count_surface_pixels(const ImageF& inv_depth, int stride);

// Central-difference gradients in intensity (or inverse-depth) units per pixel. Border
// pixels, and inverse-depth pixels next to an invalid one, get 0.
void compute_gradients(const ImageF& img, ImageF* gx, ImageF* gy);
void compute_depth_gradients(const ImageF& inv_depth, ImageF* gx, ImageF* gy);

}  // namespace rgbdtam

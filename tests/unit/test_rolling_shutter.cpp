// A rolling shutter (camera.readout_ms, depth.readout_ms): each row of an image was exposed from
// where the camera was at that row's instant (FramePyramid::row_motion), in the frame and in
// the keyframe, and the pose is the middle row's; while tracking, the motion the pose reached
// implies (PoseRowMotion). Rendered room, half size, each row rendered
// from its own pose.
#include <gtest/gtest.h>

#include "rgbdtam/core/rolling_shutter.hpp"
#include "timing_probe.hpp"

namespace rgbdtam {
namespace {

using testing::kDeg;
using testing::PoseError;

// 30 ms, a Kinect's frame, of a brisk pan (60 deg/s) and a sideways step (0.5 m/s).
Vector6d pan_over_readout() {
  Vector6d m;
  m << 0.015, 0.0, 0.0, 0.0, 1.8 * kDeg, 0.3 * kDeg;
  return m;
}

void expect_tracked_row_by_row(const char* whose, const PoseError& as_if_global,
                               const PoseError& row_by_row) {
  char ignored[96];
  std::snprintf(ignored, sizeof(ignored), "with %s rows as if exposed at once", whose);
  testing::expect_timing_modelled(ignored, as_if_global, "row by row", row_by_row);
}

class RollingShutter : public testing::TimingProbe {
 protected:
  // Both images with every row seen from its own instant's camera, the middle row's at T_w_c.
  void render_rolling(const SE3& T_w_c, const Vector6d& row_motion, FramePyramid* out) const {
    const RowMotion rows(row_motion, room_.camera.height_px);
    testing::synthetic_pyramid(room_.render_rows([&](int y) {
      return T_w_c *
             SE3::exp(static_cast<double>(rows.from_middle(static_cast<float>(y))) * row_motion);
    }),
                               p_, out);
  }

  const SE3 T_k_c_ = testing::probe_T_k_c();
};

TEST_F(RollingShutter, TheFramesRowsAreTrackedFromTheirOwnInstants) {
  FramePyramid own;
  testing::synthetic_pyramid(room_.render(SE3()), p_, &own);
  builder_.build(own, 0, 0, SE3(), &kf_);
  FramePyramid frame;
  render_rolling(T_k_c_, pan_over_readout(), &frame);
  const PoseError as_if_global = track_error(frame, T_k_c_);
  frame.set_row_motion(pan_over_readout());
  frame.set_depth_row_motion(pan_over_readout());
  expect_tracked_row_by_row("the frame's", as_if_global, track_error(frame, T_k_c_));
}

TEST_F(RollingShutter, TheKeyframesRowsAreTrackedFromTheirOwnInstants) {
  FramePyramid own;
  render_rolling(SE3(), pan_over_readout(), &own);
  own.set_row_motion(pan_over_readout());
  own.set_depth_row_motion(pan_over_readout());
  builder_.build(own, 0, 0, SE3(), &kf_);
  EXPECT_EQ(kf_.row_motion, pan_over_readout()) << "the mapper rebuilds its points with it";
  FramePyramid frame;
  testing::synthetic_pyramid(room_.render(T_k_c_), p_, &frame);
  const PoseError row_by_row = track_error(frame, T_k_c_);
  own.set_row_motion(Vector6d::Zero());
  own.set_depth_row_motion(Vector6d::Zero());
  builder_.build(own, 0, 0, SE3(), &kf_);
  expect_tracked_row_by_row("the keyframe's", track_error(frame, T_k_c_), row_by_row);
}

// The camera sped up: the velocity a frame earlier, which places the rows before the frame is
// tracked, was half what moved it over this frame. The pose each level starts from implies a
// motion from the last frame, the true pose the true one.
TEST_F(RollingShutter, TheFramesRowsFollowThePoseBeingTracked) {
  FramePyramid own;
  testing::synthetic_pyramid(room_.render(SE3()), p_, &own);
  builder_.build(own, 0, 0, SE3(), &kf_);
  const double readout_over_frame = 0.6;  // 20 ms of a 33 ms frame
  const SE3 T_w_last = T_k_c_ * SE3::exp(pan_over_readout() / readout_over_frame).inverse();
  FramePyramid frame;
  render_rolling(T_k_c_, pan_over_readout(), &frame);
  frame.set_row_motion(0.5 * pan_over_readout());
  frame.set_depth_row_motion(0.5 * pan_over_readout());
  const PoseError a_frame_late = track_error(frame, T_k_c_);
  frame.set_rows_follow_pose({T_w_last.inverse(), readout_over_frame, readout_over_frame});
  const PoseError following = track_error(frame, T_k_c_);
  testing::expect_timing_modelled("with the rows placed by the velocity a frame before",
                                  a_frame_late, "by the pose being tracked", following);
  frame.set_rows_fixed();
  EXPECT_EQ(frame.row_motions_at(T_k_c_).colour, 0.5 * pan_over_readout())
      << "fixed again: the twists set";
}

TEST(PoseRowMotion, IsTheMotionFromTheLastFrameOverEachReadout) {
  const SE3 T_w_last(so3_exp(Vector3d(0.1, 0.2, 0.3)), Vector3d(1.0, 2.0, 3.0));
  const PoseRowMotion m{T_w_last.inverse(), 0.6, 0.3};
  const RowMotions rows = m.at(T_w_last * SE3::exp(pan_over_readout()));
  EXPECT_LT((rows.colour - 0.6 * pan_over_readout()).norm(), 1e-12);
  EXPECT_LT((rows.depth - 0.3 * pan_over_readout()).norm(), 1e-12);
  // To rounding: an aarch64 build fuses the products (3e-17 there).
  EXPECT_LT(m.at(T_w_last).colour.norm(), 1e-12) << "a camera that stayed put";
}

TEST(RowMotion, MovesAPointToItsRowsCameraAndBackToFirstOrder) {
  const RowMotion rows(pan_over_readout(), 240);
  EXPECT_FLOAT_EQ(rows.from_middle(0.f), -0.5f);
  EXPECT_FLOAT_EQ(rows.from_middle(239.f), 0.5f);
  // A point 2 m ahead seen from the last row's camera, against the exact motion, and moved
  // back: what is left is second order, s^2 |w| (|w| |p| + |v|), 0.6 mm here.
  const Vector3d p(0.3, -0.2, 2.0);
  float x = 0.3f, y = -0.2f, z = 2.f;
  rows.move(-0.5f, &x, &y, &z);
  const Vector3d exact = SE3::exp(0.5 * pan_over_readout()).inverse() * p;
  EXPECT_LT((Vector3d(x, y, z) - exact).norm(), 0.001);
  EXPECT_GT((exact - p).norm(), 0.02) << "the motion moves the point";
  rows.move(0.5f, &x, &y, &z);
  EXPECT_LT((Vector3d(x, y, z) - p).norm(), 0.001);
}

}  // namespace
}  // namespace rgbdtam

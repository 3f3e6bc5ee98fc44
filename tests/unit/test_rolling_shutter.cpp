// A rolling shutter (camera.readout_ms, depth.readout_ms): each row of an image was exposed from
// where the camera was at that row's instant (FramePyramid::row_motion), in the frame and in
// the keyframe, and the pose is the middle row's. Rendered room, half size, each row rendered
// from its own pose.
#include <gtest/gtest.h>

#include "measures.hpp"
#include "rgbdtam/core/rolling_shutter.hpp"
#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/core/tracking_health.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

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
  std::printf(
      "pose error %.2f mm %.3f deg with %s rows as if exposed at once, %.2f mm %.3f deg row "
      "by row\n",
      1e3 * as_if_global.m, as_if_global.rad / kDeg, whose, 1e3 * row_by_row.m,
      row_by_row.rad / kDeg);
  EXPECT_LT(row_by_row.m, 0.001);
  EXPECT_LT(row_by_row.rad, 0.05 * kDeg);
  EXPECT_LT(row_by_row.m, 0.3 * as_if_global.m) << "the test shows nothing";
}

class RollingShutter : public ::testing::Test {
 protected:
  void SetUp() override {
    p_ = testing::synthetic_params(room_);
    p_.tracker = tracking_options(p_);
    builder_.allocate(p_.camera, p_.tracker);
    builder_.allocate_keyframe(&kf_);
    for (float& s : scales_.photometric) s = kProbeSigma;
  }

  // Both images with every row seen from its own instant's camera, the middle row's at T_w_c.
  void render_rolling(const SE3& T_w_c, const Vector6d& row_motion, FramePyramid* out) const {
    const RowMotion rows(row_motion, room_.camera.height_px);
    testing::synthetic_pyramid(room_.render_rows([&](int y) {
      return T_w_c *
             SE3::exp(static_cast<double>(rows.from_middle(static_cast<float>(y))) * row_motion);
    }),
                               p_, out);
  }

  PoseError track_error(const FramePyramid& frame, const SE3& T_k_c) {
    tracker_.allocate(kf_, p_.tracker);
    return testing::pose_error(tracker_.track(kf_, frame, SE3(), scales_).T_k_c, T_k_c);
  }

  const testing::SyntheticScene room_ = testing::SyntheticScene::half_resolution();
  Params p_;
  KeyframeBuilder builder_;
  Keyframe kf_;
  Tracker tracker_;
  ReferenceScales scales_;
  const SE3 T_k_c_{so3_exp(Vector3d(0.0, 1.0, 0.0) * kDeg), Vector3d(0.03, 0.0, 0.01)};
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

// Depth taken at another instant than colour (a Kinect streams the two unsynchronised): each
// depth image is tracked from where the camera was when it was taken (FramePyramid::T_c_d), in
// the frame and in the keyframe, and the pose is the colour image's. Rendered room, half size.
#include <gtest/gtest.h>

#include <algorithm>

#include "measures.hpp"
#include "rgbdtam/core/keyframe_aliases.hpp"
#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/core/tracking_health.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

using testing::kDeg;
using testing::PoseError;

// 15 ms of a brisk hand-held motion (0.7 m/s, 40 deg/s): where the depth camera was.
const SE3 kT_c_d(so3_exp(Vector3d(0.4, -0.3, 0.3) * kDeg), Vector3d(0.008, -0.004, 0.006));

// Tracked from where the depth was taken, the pose is the colour image's; read as if taken with
// its colour, it is not (or the test would show nothing).
void expect_tracked_where_taken(const char* whose, const PoseError& as_if_together,
                                const PoseError& at_its_instant) {
  std::printf(
      "pose error %.2f mm %.3f deg with %s depth as if taken with its colour, %.2f mm "
      "%.3f deg from where it was taken\n",
      1e3 * as_if_together.m, as_if_together.rad / kDeg, whose, 1e3 * at_its_instant.m,
      at_its_instant.rad / kDeg);
  EXPECT_LT(at_its_instant.m, 0.001);
  EXPECT_LT(at_its_instant.rad, 0.05 * kDeg);
  EXPECT_LT(at_its_instant.m, 0.3 * as_if_together.m) << "the test shows nothing";
}

class DepthInstant : public ::testing::Test {
 protected:
  void SetUp() override {
    p_ = testing::synthetic_params(room_);
    p_.tracker = tracking_options(p_);
    builder_.allocate(p_.camera, p_.tracker);
    builder_.allocate_keyframe(&kf_);
    for (float& s : scales_.photometric) s = kProbeSigma;
  }

  // The colour image seen from T_w_c and the depth image from T_w_c * T_c_d.
  void render(const SE3& T_w_c, const SE3& T_c_d, FramePyramid* out) const {
    testing::synthetic_pyramid(room_.render(T_w_c), p_, out);
    FramePyramid depth;
    testing::synthetic_pyramid(room_.render(T_w_c * T_c_d), p_, &depth);
    const ImageF& taken = depth.inverse_depth(0);
    std::copy(taken.data(), taken.data() + taken.size(), out->inverse_depth_level0().data());
    out->build_inverse_depth_levels();
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
};

TEST_F(DepthInstant, TheFramesLateDepthIsTrackedFromWhereItWasTaken) {
  FramePyramid own;
  testing::synthetic_pyramid(room_.render(SE3()), p_, &own);
  builder_.build(own, 0, 0, SE3(), &kf_);
  const SE3 T_k_c(so3_exp(Vector3d(0.0, 1.0, 0.0) * kDeg), Vector3d(0.03, 0.0, 0.01));
  FramePyramid frame;
  render(T_k_c, kT_c_d, &frame);
  const PoseError as_if_together = track_error(frame, T_k_c);
  frame.set_T_c_d(kT_c_d);
  expect_tracked_where_taken("the frame's", as_if_together, track_error(frame, T_k_c));
}

TEST_F(DepthInstant, TheKeyframesLateDepthIsTrackedFromWhereItWasTaken) {
  FramePyramid own;
  render(SE3(), kT_c_d, &own);
  own.set_T_c_d(kT_c_d);
  builder_.build(own, 0, 0, SE3(), &kf_);
  EXPECT_EQ(kf_.T_k_kd.translation(), kT_c_d.translation());
  const SE3 T_k_c(so3_exp(Vector3d(0.0, 1.0, 0.0) * kDeg), Vector3d(0.03, 0.0, 0.01));
  FramePyramid frame;
  testing::synthetic_pyramid(room_.render(T_k_c), p_, &frame);
  const PoseError at_its_instant = track_error(frame, T_k_c);
  kf_.T_k_kd = SE3();
  expect_tracked_where_taken("the keyframe's", track_error(frame, T_k_c), at_its_instant);
}

TEST_F(DepthInstant, ADepthPoseIsForgottenWithTheDepth) {
  FramePyramid frame;
  render(SE3(), kT_c_d, &frame);
  frame.set_T_c_d(kT_c_d);
  frame.clear_depth();
  EXPECT_EQ(frame.T_c_d().translation(), Vector3d::Zero());
}

}  // namespace
}  // namespace rgbdtam

// Depth taken at another instant than colour (a Kinect streams the two unsynchronised): each
// depth image is tracked from where the camera was when it was taken (FramePyramid::T_c_d), in
// the frame and in the keyframe, and the pose is the colour image's. Rendered room, half size.
#include <gtest/gtest.h>

#include <algorithm>

#include "timing_probe.hpp"

namespace rgbdtam {
namespace {

using testing::kDeg;
using testing::PoseError;

// 15 ms of a brisk hand-held motion (0.7 m/s, 40 deg/s): where the depth camera was.
const SE3 kT_c_d(so3_exp(Vector3d(0.4, -0.3, 0.3) * kDeg), Vector3d(0.008, -0.004, 0.006));

// Tracked from where the depth was taken, the pose is the colour image's.
void expect_tracked_where_taken(const char* whose, const PoseError& as_if_together,
                                const PoseError& at_its_instant) {
  char ignored[96];
  std::snprintf(ignored, sizeof(ignored), "with %s depth as if taken with its colour", whose);
  testing::expect_timing_modelled(ignored, as_if_together, "from where it was taken",
                                  at_its_instant);
}

class DepthInstant : public testing::TimingProbe {
 protected:
  // The colour image seen from T_w_c and the depth image from T_w_c * T_c_d.
  void render(const SE3& T_w_c, const SE3& T_c_d, FramePyramid* out) const {
    testing::synthetic_pyramid(room_.render(T_w_c), p_, out);
    FramePyramid depth;
    testing::synthetic_pyramid(room_.render(T_w_c * T_c_d), p_, &depth);
    const ImageF& taken = depth.inverse_depth(0);
    std::copy(taken.data(), taken.data() + taken.size(), out->inverse_depth_level0().data());
    out->build_inverse_depth_levels();
  }
};

TEST_F(DepthInstant, TheFramesLateDepthIsTrackedFromWhereItWasTaken) {
  FramePyramid own;
  testing::synthetic_pyramid(room_.render(SE3()), p_, &own);
  builder_.build(own, 0, 0, SE3(), &kf_);
  const SE3 T_k_c = testing::probe_T_k_c();
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
  const SE3 T_k_c = testing::probe_T_k_c();
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

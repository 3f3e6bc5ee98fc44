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

// 15 ms of a brisk hand-held motion (0.7 m/s, 40 deg/s): where the depth camera was.
const SE3 kT_c_d(so3_exp(Vector3d(0.4, -0.3, 0.3) * kDeg), Vector3d(0.008, -0.004, 0.006));

// A tracked pose's error against the truth.
struct PoseError {
  double m = 0.0, rad = 0.0;
};

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
    const TrackResult r = tracker_.track(kf_, frame, SE3(), scales_);
    const SE3 error = T_k_c.inverse() * r.T_k_c;
    return {error.translation().norm(), so3_log(error.quaternion()).norm()};
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

TEST_F(DepthInstant, DepthMovedToTheColoursInstantIsTheDepthSeenFromThere) {
  FramePyramid taken, seen;
  render(SE3(), kT_c_d, &taken);
  testing::synthetic_pyramid(room_.render(SE3()), p_, &seen);
  ImageF moved;
  moved.allocate(taken.inverse_depth(0).width(), taken.inverse_depth(0).height());
  move_inverse_depth(taken.inverse_depth(0), taken.intrinsics(0), kT_c_d, &moved);
  // Pixel by pixel against the depth rendered from the colour camera: the same surfaces, but for
  // outlines and the holes where the depth camera did not see.
  const ImageF& truth = seen.inverse_depth(0);
  int both = 0, close = 0, fine = 0, holes = 0, as_taken_close = 0;
  for (int i = 0; i < truth.size(); ++i) {
    const float t = truth.data()[i];
    if (t <= 0.f) continue;
    const float m = moved.data()[i];
    if (m <= 0.f) {
      ++holes;
      continue;
    }
    ++both;
    close += std::abs(m - t) < 0.01f * t ? 1 : 0;
    fine += std::abs(m - t) < 0.001f * t ? 1 : 0;
    const float as_taken = taken.inverse_depth(0).data()[i];
    as_taken_close += std::abs(as_taken - t) < 0.01f * t ? 1 : 0;
  }
  std::printf(
      "%d pixels: %.1f %% within 1 %% of the truth moved (%.1f %% within 0.1 %%), %.1f %% as "
      "taken, %d holes\n",
      both, 100.0 * close / both, 100.0 * fine / both, 100.0 * as_taken_close / both, holes);
  EXPECT_GT(close, 0.97 * both);
  // Each pixel's value taken at its own centre along the surface, not up to half a pixel off
  // (65 % within 0.1 % so).
  EXPECT_GT(fine, 0.95 * both);
  EXPECT_LT(as_taken_close, 0.9 * both) << "the test shows nothing";
  EXPECT_LT(holes, truth.size() * 3 / 100);
}

TEST_F(DepthInstant, TheKeyframesPhotometricPointsTakeTheDepthMovedToTheColoursInstant) {
  FramePyramid own;
  render(SE3(), kT_c_d, &own);
  own.set_T_c_d(kT_c_d);
  const SE3 T_k_c(so3_exp(Vector3d(0.0, 1.0, 0.0) * kDeg), Vector3d(0.03, 0.0, 0.01));
  FramePyramid frame;
  testing::synthetic_pyramid(room_.render(T_k_c), p_, &frame);
  builder_.build(own, 0, 0, SE3(), &kf_);
  const PoseError where_taken = track_error(frame, T_k_c);
  FramePyramid moved;
  moved.allocate(p_.camera, p_.sensor.depth_factor, p_.sensor.depth_range);
  move_inverse_depth(own.inverse_depth(0), own.intrinsics(0), kT_c_d,
                     &moved.inverse_depth_level0());
  moved.build_inverse_depth_levels();
  builder_.build(own, 0, 0, SE3(), &kf_, &moved);
  const PoseError at_colours_instant = track_error(frame, T_k_c);
  std::printf(
      "pose error %.2f mm %.3f deg with the photometric points' depth where it was taken, "
      "%.2f mm %.3f deg moved to the colour's instant\n",
      1e3 * where_taken.m, where_taken.rad / kDeg, 1e3 * at_colours_instant.m,
      at_colours_instant.rad / kDeg);
  EXPECT_LT(at_colours_instant.m, 0.6 * where_taken.m);
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

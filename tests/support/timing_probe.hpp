#pragma once
// Tests of when an image was taken (depth at its own instant, a rolling shutter's rows): one
// keyframe of the rendered room at half size, one frame tracked against it, and the pose's
// error with the timing modelled against without.
#include <gtest/gtest.h>

#include <cstdio>

#include "measures.hpp"
#include "rgbdtam/core/keyframe_aliases.hpp"
#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/core/tracking_health.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam::testing {

// The frame's true pose in the keyframe: a step and a turn of a degree.
inline SE3 probe_T_k_c() {
  return SE3(so3_exp(Vector3d(0.0, 1.0, 0.0) * kDeg), Vector3d(0.03, 0.0, 0.01));
}

// With the timing modelled the pose is within a millimetre and 0.05 degree; without, it is not
// (or the test would show nothing). The two phrases say what each error is of.
inline void expect_timing_modelled(const char* ignored, const PoseError& without,
                                   const char* modelled, const PoseError& with) {
  std::printf("pose error %.2f mm %.3f deg %s, %.2f mm %.3f deg %s\n", 1e3 * without.m,
              without.rad / kDeg, ignored, 1e3 * with.m, with.rad / kDeg, modelled);
  EXPECT_LT(with.m, 0.001);
  EXPECT_LT(with.rad, 0.05 * kDeg);
  EXPECT_LT(with.m, 0.3 * without.m) << "the test shows nothing";
}

class TimingProbe : public ::testing::Test {
 protected:
  void SetUp() override {
    p_ = synthetic_params(room_);
    p_.tracker = tracking_options(p_);
    builder_.allocate(p_.camera, p_.tracker);
    builder_.allocate_keyframe(&kf_);
    for (float& s : scales_.photometric) s = kProbeSigma;
  }

  PoseError track_error(const FramePyramid& frame, const SE3& T_k_c) {
    tracker_.allocate(kf_, p_.tracker);
    return pose_error(tracker_.track(kf_, frame, SE3(), scales_).T_k_c, T_k_c);
  }

  const SyntheticScene room_ = SyntheticScene::half_resolution();
  Params p_;
  KeyframeBuilder builder_;
  Keyframe kf_;
  Tracker tracker_;
  ReferenceScales scales_;
};

}  // namespace rgbdtam::testing

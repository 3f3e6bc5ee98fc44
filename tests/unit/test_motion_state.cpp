// The motion state's clocks, driven by frame stamps: when a jump withholds poses, and from when a
// loss is counted.
#include <gtest/gtest.h>

#include "measures.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/runtime/tracking/motion_state.hpp"

namespace rgbdtam {
namespace {

using testing::kMs;
constexpr int64_t kWindowNs = 500 * kMs;  // health.reset_after_lost_ms

MotionState tracked_until(int64_t t_ns) {
  MotionState m;
  m.init(true, kWindowNs);
  m.begin(SE3(), 0);
  for (int64_t t = 33 * kMs; t <= t_ns; t += 33 * kMs) m.track(SE3(), t, true);
  return m;
}

TEST(MotionState, ARelocalisationWithholdsPosesUntilTheWindowAfterTheLastValidOneHasPassed) {
  MotionState m = tracked_until(990 * kMs);
  const int64_t last_valid_ns = m.last_tracked_ns();
  const uint32_t resets = m.reset_counter();
  // Lost for two frames, then found somewhere the motion since was not measured.
  m.begin(SE3(Eigen::Quaterniond::Identity(), Vector3d(0.6, 0.0, 0.0)), last_valid_ns + 100 * kMs);
  m.jumped(last_valid_ns);
  EXPECT_EQ(m.reset_counter(), resets + 1);
  EXPECT_TRUE(m.withheld(last_valid_ns + 100 * kMs));
  EXPECT_TRUE(m.withheld(last_valid_ns + kWindowNs)) << "a pose exactly a window later is compared";
  EXPECT_FALSE(m.withheld(last_valid_ns + kWindowNs + 1));
}

TEST(MotionState, AJumpWithNoPoseBeforeItWithholdsNothing) {
  MotionState m;
  m.init(true, kWindowNs);
  m.begin(SE3(), 100 * kMs);  // found in a loaded map: nothing was sent before
  m.jumped(-1);
  EXPECT_FALSE(m.withheld(100 * kMs));
}

TEST(MotionState, ALossAfterAPoseFoundWithoutTrackingIsCountedFromItsOwnFirstFrame) {
  MotionState m = tracked_until(990 * kMs);
  EXPECT_EQ(m.lost_for_ns(1023 * kMs), 0);  // lost from here ...
  EXPECT_EQ(m.lost_for_ns(1056 * kMs), 33 * kMs);
  m.begin(SE3(), 1089 * kMs);  // ... relocalised onto a new keyframe ...
  EXPECT_EQ(m.lost_for_ns(1122 * kMs), 0) << "... and lost again: a new loss, not the old one";
}

// A small correction sent at once is not withheld: the next pose carries the jump, so that its
// covariance can cover it.
TEST(MotionState, ASmallCorrectionSentAtOnceIsFlaggedWithHowFarItMovedTheCamera) {
  MotionState m = tracked_until(990 * kMs);
  const SE3 delta(so3_exp(Vector3d(0.0, 0.0, 0.01)), Vector3d(0.012, 0.0, 0.0));
  // The camera sits at the world's origin: the poses sent jump by delta.
  m.correct(delta, delta, 0.05, 2.5 * M_PI / 180.0);
  m.correct(delta, delta, 0.05, 2.5 * M_PI / 180.0);
  EXPECT_FALSE(m.withheld(1023 * kMs));
  const CorrectionJump jump = m.take_correction();
  EXPECT_EQ(jump.flags, kLoopCorrected | kReset);
  EXPECT_NEAR(jump.translation_m, 2 * 0.012, 1e-9);
  EXPECT_NEAR(jump.rotation_rad, 2 * 0.01, 1e-9);
  EXPECT_EQ(m.take_correction().flags, 0u) << "taken once";
}

TEST(MotionState, ALargeCorrectionWithholdsTheConsumersWindowAndABlendedOneNothing) {
  MotionState m = tracked_until(990 * kMs);
  const uint32_t resets = m.reset_counter();
  const SE3 delta(Eigen::Quaterniond::Identity(), Vector3d(0.0, 0.08, 0.0));
  m.correct_blended(delta);
  EXPECT_NEAR(m.T_w_last().translation().y(), 0.08, 1e-12) << "tracking moves at once";
  EXPECT_EQ(m.reset_counter(), resets);
  EXPECT_FALSE(m.withheld(1023 * kMs));
  EXPECT_EQ(m.take_correction().flags, static_cast<uint32_t>(kLoopCorrected));
  m.correct(delta, delta, 0.05, 2.5 * M_PI / 180.0);
  EXPECT_EQ(m.reset_counter(), resets + 1);
  EXPECT_TRUE(m.withheld(m.last_ns() + kWindowNs));
  EXPECT_FALSE(m.withheld(m.last_ns() + kWindowNs + 1));
  EXPECT_EQ(m.counters().loop_corrections, 2u);
  EXPECT_EQ(m.counters().blended_corrections, 1u);
}

// Loop corrections, blended or not, move the camera's world by what they measured: a pose from
// before them maps into it. A restart or a relocalisation begins a new epoch, which nothing maps.
TEST(MotionState, TheMapFrameComposesCorrectionsWithinAnEpoch) {
  MotionState m = tracked_until(990 * kMs);
  const MapFrame before = m.map_frame();
  const SE3 first(so3_exp(Vector3d(0.0, 0.02, 0.0)), Vector3d(0.0, 0.01, 0.0));
  const SE3 second(so3_exp(Vector3d(0.01, 0.0, 0.0)), Vector3d(0.03, 0.0, -0.02));
  m.correct_blended(first);
  m.correct(second, second, 0.05, 2.5 * M_PI / 180.0);
  EXPECT_FALSE(m.map_frame().same_as(before));
  SE3 T_now_before;
  ASSERT_TRUE(m.map_frame().moved_from(before, &T_now_before));
  const SE3 expected = second * first;
  EXPECT_LT((T_now_before.translation() - expected.translation()).norm(), 1e-12);
  EXPECT_LT(so3_log((T_now_before.inverse() * expected).quaternion()).norm(), 1e-12);

  const MapFrame corrected = m.map_frame();
  m.jumped(m.last_ns());
  EXPECT_FALSE(m.map_frame().moved_from(corrected, &T_now_before)) << "a relocalisation";
  const MapFrame relocalised = m.map_frame();
  m.restart(m.last_ns() + 600 * kMs);
  EXPECT_FALSE(m.map_frame().moved_from(relocalised, &T_now_before)) << "a restart";
  EXPECT_TRUE(m.map_frame().moved_from(m.map_frame(), &T_now_before));
  EXPECT_LT(T_now_before.translation().norm(), 1e-12);
}

}  // namespace
}  // namespace rgbdtam

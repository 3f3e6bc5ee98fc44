// Two poses compared on the keyframe points both see (Tracker::fit_on_common_points), on the
// rendered textured room: the comparison that replaced each pose's mean over its own points in
// view when two minima compete (the latter favours a pose that sees only a sliver). And where
// the coarse levels take a candidate (Tracker::align), which spares the finer ones a candidate
// back in the pose's own basin.
#include <gtest/gtest.h>

#include "rgbdtam/core/keyframe_aliases.hpp"
#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/core/tracking_health.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

class CommonFit : public ::testing::Test {
 protected:
  void SetUp() override {
    const testing::SyntheticScene room = testing::SyntheticScene::half_resolution();
    Params p = testing::synthetic_params(room);
    p.tracker = tracking_options(p);
    FramePyramid own;
    testing::synthetic_pyramid(room.render(SE3()), p, &own);
    builder_.allocate(p.camera, p.tracker);
    builder_.allocate_keyframe(&kf_);
    builder_.build(own, 0, 0, SE3(), &kf_);
    T_k_c_ = SE3(Eigen::Quaterniond::Identity(), Vector3d(0.03, 0.0, 0.0));
    testing::synthetic_pyramid(room.render(T_k_c_), p, &frame_);
    tracker_.allocate(kf_, p.tracker);
    for (float& s : scales_.photometric) s = kProbeSigma;
  }

  void compare(const SE3& a, const SE3& b, double* cost_a, double* cost_b) {
    tracker_.fit_on_common_points(kf_, frame_, a, b, 0, scales_, kAllTerms, cost_a, cost_b);
  }

  KeyframeBuilder builder_;
  Keyframe kf_;
  FramePyramid frame_;
  Tracker tracker_;
  ReferenceScales scales_;
  SE3 T_k_c_;
};

TEST_F(CommonFit, APoseComparedWithItselfFitsExactlyAsWell) {
  double a = 0.0, b = 0.0;
  compare(T_k_c_, T_k_c_, &a, &b);
  EXPECT_TRUE(std::isfinite(a));
  EXPECT_EQ(a, b);
}

TEST_F(CommonFit, TheTruePoseFitsTheSharedPointsBetterWhicheverIsNamedFirst) {
  const SE3 off = T_k_c_ * SE3(Eigen::Quaterniond::Identity(), Vector3d(0.08, 0.0, 0.0));
  double true_first = 0.0, off_second = 0.0, off_first = 0.0, true_second = 0.0;
  compare(T_k_c_, off, &true_first, &off_second);
  compare(off, T_k_c_, &off_first, &true_second);
  EXPECT_LT(true_first, off_second);
  EXPECT_DOUBLE_EQ(true_first, true_second) << "the same shared points either way";
  EXPECT_DOUBLE_EQ(off_second, off_first);
}

TEST_F(CommonFit, PosesThatShareNoPointAreNotComparable) {
  // Turned half a circle: the keyframe is behind the camera.
  const SE3 behind = T_k_c_ * SE3(so3_exp(Vector3d(0.0, M_PI, 0.0)), Vector3d::Zero());
  double a = 0.0, b = 0.0;
  compare(T_k_c_, behind, &a, &b);
  EXPECT_FALSE(std::isfinite(a));
  EXPECT_FALSE(std::isfinite(b));
}

TEST_F(CommonFit, AlignmentDownToTheFinestLevelIsTracking) {
  const SE3 guess = T_k_c_ * SE3(Eigen::Quaterniond::Identity(), Vector3d(0.0, 0.01, 0.0));
  const SE3 aligned = tracker_.align(kf_, frame_, guess, kAllTerms, 0);
  const TrackResult tracked = tracker_.track(kf_, frame_, guess, scales_);
  EXPECT_EQ(aligned.translation(), tracked.T_k_c.translation());
  EXPECT_EQ(aligned.rotation(), tracked.T_k_c.rotation());
}

TEST_F(CommonFit, TheCoarseLevelsBringACandidateInThePosesBasinBackToIt) {
  const TrackResult pose = tracker_.track(kf_, frame_, T_k_c_, scales_);
  ASSERT_TRUE(same_pose(pose.T_k_c, T_k_c_));
  // 3 cm aside, beyond what makes two poses the same, within the coarse levels' basin.
  const SE3 candidate = pose.T_k_c * SE3(Eigen::Quaterniond::Identity(), Vector3d(0.03, 0.0, 0.0));
  ASSERT_FALSE(same_pose(candidate, pose.T_k_c));
  constexpr int kProbingLevel = 2;
  EXPECT_TRUE(
      same_pose(tracker_.align(kf_, frame_, candidate, kAllTerms, kProbingLevel), pose.T_k_c));
}

}  // namespace
}  // namespace rgbdtam

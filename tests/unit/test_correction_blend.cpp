// Loop corrections blended into the poses sent, driven by frame stamps: the camera's extra
// motion stays within the rate, the poses sent arrive on the corrected map, and what the blend
// cannot take up is left to a jump with the reset counter.
#include <gtest/gtest.h>

#include "rgbdtam/runtime/tracking/correction_blend.hpp"

namespace rgbdtam {
namespace {

constexpr int64_t kFrameNs = 33'333'333;
constexpr double kFrameS = kFrameNs * 1e-9;
const BlendLimits kLimits{0.1, 5.0 * M_PI / 180.0, 1.0};
// What a consumer differencing poses over 0.5 s may see beyond the camera's motion: the rates'
// half second, half the false-valid tolerance.
constexpr double kHalfSecondM = 0.05;
constexpr double kHalfSecondRad = 2.5 * M_PI / 180.0;

// The true camera: 3 m from the world's origin, moving at 0.5 m/s and turning at 20 deg/s, so
// that a blend done in the world's frame would swing it.
SE3 truth(int k) {
  const double t = k * kFrameS;
  return SE3(so3_exp(Vector3d(0.0, 20.0 * M_PI / 180.0 * t, 0.0)),
             Vector3d(3.0 + 0.5 * t, 0.0, 1.0));
}

double angle(const SE3& T) { return so3_log(T.quaternion()).norm(); }

TEST(CorrectionBlend, APoseSentMovesOntoTheCorrectedMapWithinTheRate) {
  CorrectionBlend blend;
  blend.init(kLimits);
  // 8.5 cm and 4 degrees at the camera, the world moved about its own origin: more than a half
  // second's worth, within the longest blend.
  const int corrected_at = 10;
  const SE3 at_camera(so3_exp(Vector3d(0.0, 0.0, 4.0 * M_PI / 180.0)), Vector3d(0.07, 0.048, 0.0));
  const SE3 delta = truth(corrected_at - 1) * at_camera * truth(corrected_at - 1).inverse();
  constexpr int kFrames = 60;
  SE3 sent[kFrames];
  for (int k = 0; k < kFrames; ++k) {
    SE3 tracked = truth(k);
    if (k == corrected_at) {
      SE3 jump;
      ASSERT_TRUE(blend.absorb(delta, truth(k - 1), &jump));
      EXPECT_TRUE(blend.blending());
    }
    if (k >= corrected_at) tracked = delta * truth(k);
    sent[k] = blend.sent(tracked, k * kFrameNs, 0);
  }
  ASSERT_GT(delta.translation().norm(), kLimits.rate_m_per_s * kLimits.max_s)
      << "the world moves further than the camera";
  for (int k = 1; k < kFrames; ++k) {
    // What the poses sent say the camera did, against what it did.
    const SE3 extra =
        (truth(k - 1).inverse() * truth(k)).inverse() * (sent[k - 1].inverse() * sent[k]);
    EXPECT_LE(extra.translation().norm(), kLimits.rate_m_per_s * kFrameS * 1.05 + 1e-9) << k;
    EXPECT_LE(angle(extra), kLimits.rate_rad_per_s * kFrameS * 1.05 + 1e-9) << k;
  }
  for (int k = 1; k < kFrames; ++k) {
    // Over the 0.5 s a consumer differences, about half the false-valid tolerance: the camera's
    // own 25 cm and 10 degrees in that time turn the steps' rotation into 3 mm more.
    for (int j = std::max(0, k - 15); j < k; ++j) {
      const SE3 e = (truth(j).inverse() * truth(k)).inverse() * (sent[j].inverse() * sent[k]);
      EXPECT_LE(e.translation().norm(), kHalfSecondM * 1.1) << j << " " << k;
      EXPECT_LE(angle(e), kHalfSecondRad * 1.05) << j << " " << k;
    }
  }
  EXPECT_LT((sent[corrected_at].translation() - truth(corrected_at).translation()).norm(), 0.01)
      << "no jump at the correction";
  // Longer than the half second a 5 cm blend took, within the longest blend.
  int done = corrected_at;
  while (done < kFrames && !within(sent[done].inverse() * delta * truth(done), 1e-9, 1e-9)) ++done;
  EXPECT_GT((done - corrected_at + 1) * kFrameS, 0.5);
  EXPECT_LE((done - corrected_at + 1) * kFrameS, kLimits.max_s + kFrameS);
  EXPECT_FALSE(blend.blending());
  EXPECT_LT((sent[done].translation() - (delta * truth(done)).translation()).norm(), 1e-9);
  EXPECT_LT(angle(sent[done].inverse() * delta * truth(done)), 1e-9);
}

TEST(CorrectionBlend, ACorrectionBeyondTheLimitsIsSentAtOnceWithWhatWasStillBlending) {
  CorrectionBlend blend;
  blend.init(kLimits);
  const SE3 T_w_c = truth(0);
  (void)blend.sent(T_w_c, 0, 0);
  const SE3 small(Eigen::Quaterniond::Identity(), Vector3d(0.06, 0.0, 0.0));
  SE3 jump;
  ASSERT_TRUE(blend.absorb(small, T_w_c, &jump));
  // Not sent yet, and 6 cm more: 12 cm from the last pose sent, more than 1 s at 0.1 m/s.
  EXPECT_FALSE(blend.absorb(small, small * T_w_c, &jump));
  EXPECT_FALSE(blend.blending());
  EXPECT_NEAR(jump.translation().norm(), 0.12, 1e-9);
  const SE3 tracked = small * small * T_w_c;
  const SE3 out = blend.sent(tracked, kFrameNs, 1);
  EXPECT_LT((out.translation() - tracked.translation()).norm(), 1e-12);
}

TEST(CorrectionBlend, AResetEndsTheBlendAndRateZeroBlendsNothing) {
  CorrectionBlend blend;
  blend.init(kLimits);
  const SE3 delta(Eigen::Quaterniond::Identity(), Vector3d(0.0, 0.04, 0.0));
  (void)blend.sent(truth(0), 0, 3);
  SE3 jump;
  ASSERT_TRUE(blend.absorb(delta, truth(0), &jump));
  // Relocalised: the consumers start again, so the pose sent is tracking's.
  const SE3 out = blend.sent(delta * truth(1), kFrameNs, 4);
  EXPECT_FALSE(blend.blending());
  EXPECT_LT((out.translation() - (delta * truth(1)).translation()).norm(), 1e-12);

  CorrectionBlend at_once;
  at_once.init({0.0, 0.0, kLimits.max_s});
  EXPECT_FALSE(at_once.absorb(delta, truth(0), &jump));
  EXPECT_NEAR(jump.translation().norm(), 0.04, 1e-9);
}

}  // namespace
}  // namespace rgbdtam

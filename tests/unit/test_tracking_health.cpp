// Each health check on its own: quiet on a healthy result, triggered by exactly its cause.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "rgbdtam/core/tracking_health.hpp"

namespace rgbdtam {
namespace {

// What a well-tracked frame of fr1_xyz looks like (medians measured there).
TrackResult healthy() {
  TrackResult r;
  r.state = TrackingState::kOk;
  r.terms = kAllTerms;
  r.residuals_used = 20000;
  r.photometric_sigma = 0.04;
  r.photometric_agreement = 0.23;
  r.geometric_agreement = 0.02;
  r.photometric_inliers = 0.92;
  r.geometric_inliers = 0.98;
  r.translation_std_m = 0.12e-3;
  r.rotation_std_rad = 0.006 * M_PI / 180.0;
  return r;
}

// 2 cm and 1 degree in a 30 Hz frame: a brisk hand-held motion.
HealthContext after_one_frame() {
  HealthContext c;
  c.typical_sigma = 0.04;
  c.T_last_current = SE3(so3_exp(Vector3d(0, M_PI / 180.0, 0)), Vector3d(0.02, 0, 0));
  c.dt_s = 1.0 / 30.0;
  return c;
}

TEST(TrackingHealth, ADirectionTheDepthLeavesFreeNeedsTheImageToDetermineIt) {
  HealthLimits limits;
  limits.covariance_scale = 5000.0;
  TrackResult r = healthy();
  r.depth_degenerate = true;
  // A textured wall: the image determines the wall's in-plane motion to 0.4 cm (reported).
  r.weak_direction_std_m = 0.004 / std::sqrt(limits.covariance_scale);
  EXPECT_EQ(failed_health_checks(r, after_one_frame(), limits), 0u);
  r.weak_direction_std_m = 0.012 / std::sqrt(limits.covariance_scale);
  EXPECT_EQ(failed_health_checks(r, after_one_frame(), limits), kWeakDirection);
  // Where the depth determines every direction, the same spread is no concern of this check.
  r.depth_degenerate = false;
  EXPECT_EQ(failed_health_checks(r, after_one_frame(), limits), 0u);
  char text[64];
  describe_health(kWeakDirection, text, sizeof(text));
  EXPECT_STREQ(text, "weak direction");
}

TEST(TrackingHealth, AHealthyFramePassesEveryCheck) {
  EXPECT_EQ(failed_health_checks(healthy(), after_one_frame(), HealthLimits()), 0u);
  char text[64];
  describe_health(0, text, sizeof(text));
  EXPECT_STREQ(text, "healthy");
}

TEST(TrackingHealth, EachCheckTriggersOnItsOwnCause) {
  const HealthLimits limits;
  struct Case {
    const char* name;
    void (*spoil)(TrackResult*, HealthContext*);
    uint32_t expected;
  };
  const Case cases[] = {
      {"too few residuals", [](TrackResult* r, HealthContext*) { r->residuals_used = 50; },
       kFewResiduals},
      {"solver gave up", [](TrackResult* r, HealthContext*) { r->state = TrackingState::kLost; },
       kFewResiduals},
      // An unrelated image gives sqrt(2).
      {"photometric agreement",
       [](TrackResult* r, HealthContext*) { r->photometric_agreement = 1.4; }, kPhotometricMisfit},
      {"photometric inliers", [](TrackResult* r, HealthContext*) { r->photometric_inliers = 0.4; },
       kPhotometricMisfit},
      {"geometric agreement", [](TrackResult* r, HealthContext*) { r->geometric_agreement = 1.2; },
       kGeometricMisfit},
      // A geometric fit sliding along a plane: the inliers give it away.
      {"geometric inliers", [](TrackResult* r, HealthContext*) { r->geometric_inliers = 0.6; },
       kGeometricMisfit},
      {"cost jumped", [](TrackResult* r, HealthContext*) { r->photometric_sigma = 0.2; },
       kCostAboveTypical},
      {"translation undetermined",
       [](TrackResult* r, HealthContext*) { r->translation_std_m = 0.02; }, kIllConditioned},
      {"rotation undetermined",
       [](TrackResult* r, HealthContext*) { r->rotation_std_rad = 1.0 * M_PI / 180.0; },
       kIllConditioned},
      // The depth leaves a direction free (a corridor's axis) and the image barely determines it
      // (these limits leave the information uncalibrated).
      {"a corridor's axis undetermined",
       [](TrackResult* r, HealthContext*) {
         r->depth_degenerate = true;
         r->weak_direction_std_m = 0.02;
       },
       kWeakDirection},
      {"4 m/s",
       [](TrackResult*, HealthContext* c) {
         c->T_last_current = SE3(Eigen::Quaterniond::Identity(), Vector3d(0, 0, 4.0 / 30.0));
       },
       kTooFast},
      {"400 deg/s",
       [](TrackResult*, HealthContext* c) {
         c->T_last_current =
             SE3(so3_exp(Vector3d(0, 0, 400.0 / 30.0 * M_PI / 180.0)), Vector3d::Zero());
       },
       kTooFast},
      {"NaN in the pose",
       [](TrackResult* r, HealthContext*) {
         r->T_k_c = SE3(Eigen::Quaterniond::Identity(),
                        Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0));
       },
       kFewResiduals},
      {"NaN agreement",
       [](TrackResult* r, HealthContext*) {
         r->photometric_agreement = std::numeric_limits<double>::quiet_NaN();
       },
       kPhotometricMisfit},
  };
  for (const Case& c : cases) {
    TrackResult r = healthy();
    HealthContext context = after_one_frame();
    c.spoil(&r, &context);
    EXPECT_EQ(failed_health_checks(r, context, limits), c.expected) << c.name;
  }
}

TEST(TrackingHealth, AnUnusedTermIsNotJudgedAndNoHistoryMeansNoRatio) {
  TrackResult r = healthy();
  r.terms = kGeometricTerm;  // the photometric term was dropped
  r.photometric_agreement = 1.5;
  r.photometric_inliers = 0.1;
  r.photometric_sigma = 1.0;
  EXPECT_EQ(failed_health_checks(r, after_one_frame(), HealthLimits()), 0u);
  // Without an earlier pose or a typical scale, only what the frame shows itself is judged.
  r = healthy();
  r.photometric_sigma = 0.5;
  HealthContext first;
  EXPECT_EQ(failed_health_checks(r, first, HealthLimits()), 0u);
}

TEST(TrackingHealth, TheDescriptionNamesEveryFailedCheckAndFitsItsBuffer) {
  char text[128];
  describe_health(kPhotometricMisfit | kTooFast, text, sizeof(text));
  EXPECT_STREQ(text, "photometric misfit, too fast");
  char small[12];
  describe_health(kPhotometricMisfit | kGeometricMisfit, small, sizeof(small));
  EXPECT_LT(std::string(small).size(), sizeof(small));
}

}  // namespace

namespace {
TEST(TrackingHealth, AStepBeyondWhatAccelerationAllowsFromThePredictionIsTooFast) {
  HealthLimits limits;  // 20 m/s^2
  TrackResult r;
  r.state = TrackingState::kOk;
  r.residuals_used = 1000;
  HealthContext c;
  c.dt_s = 1.0 / 30;
  c.predicted = true;
  // 20 m/s^2 over a 30 Hz frame: 2.2 cm, and the estimates' own 2 cm; at 10 Hz, 22 cm.
  EXPECT_NEAR(prediction_reach_m(c.dt_s, limits), 0.0422, 1e-4);
  EXPECT_NEAR(prediction_reach_m(0.1, limits), 0.22, 1e-9);
  c.from_prediction_m = 0.04;
  EXPECT_EQ(failed_health_checks(r, c, limits) & kTooFast, 0u);
  c.from_prediction_m = 0.05;
  EXPECT_NE(failed_health_checks(r, c, limits) & kTooFast, 0u);
  c.predicted = false;  // without a velocity, only the speed limit holds
  EXPECT_EQ(failed_health_checks(r, c, limits) & kTooFast, 0u);
}

TEST(TrackingHealth, TwoEstimatesAFewMillimetresApartAreTheSamePose) {
  const SE3 a(so3_exp(Vector3d(0.1, 0.2, 0.3)), Vector3d(1, 2, 3));
  EXPECT_TRUE(same_pose(a, a * SE3(Eigen::Quaterniond::Identity(), Vector3d(0.01, 0, 0))));
  EXPECT_FALSE(same_pose(a, a * SE3(Eigen::Quaterniond::Identity(), Vector3d(0.03, 0, 0))));
  EXPECT_FALSE(same_pose(a, a * SE3(so3_exp(Vector3d(0, 0.03, 0)), Vector3d::Zero())));
  char why[64];
  describe_health(kAmbiguous, why, sizeof(why));
  EXPECT_STREQ(why, "ambiguous");
  describe_health(kAmbiguous | kBeyondSearch, why, sizeof(why));
  EXPECT_STREQ(why, "ambiguous, beyond search");
}
}  // namespace

}  // namespace rgbdtam

#include "measures.hpp"
#include "rgbdtam/core/attitude.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rgbdtam {
namespace {

using testing::kDeg;

Eigen::Quaterniond turn(const Vector3d& axis, double angle_rad) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, axis.normalized()));
}

// A body turning about its down axis at rate_rad_s, from heading 0, sampled every period_ns.
AttitudeHistory yawing(double rate_rad_s, int64_t period_ns, int samples) {
  AttitudeHistory h;
  for (int i = 0; i < samples; ++i) {
    AttitudeSample s;
    s.t_ns = i * period_ns;
    s.q_n_b = turn(Vector3d::UnitZ(), rate_rad_s * s.t_ns * 1e-9);
    s.rate_b_rad_s = Vector3d(0, 0, rate_rad_s);
    EXPECT_TRUE(h.add(s));
  }
  return h;
}

TEST(Attitude, InterpolatesBetweenSamplesAndCarriesOnByTheRatesBriefly) {
  const AttitudeHistory h = yawing(2.0, 20'000'000, 10);  // 50 Hz, 2 rad/s, 0 .. 180 ms
  Eigen::Quaterniond q;
  ASSERT_TRUE(h.at(33'000'000, &q));
  EXPECT_NEAR(angle_between(q, turn(Vector3d::UnitZ(), 2.0 * 0.033)), 0, 1e-9);
  ASSERT_TRUE(h.at(200'000'000, &q)) << "20 ms past the newest: carried on by its rate";
  EXPECT_NEAR(angle_between(q, turn(Vector3d::UnitZ(), 2.0 * 0.2)), 0, 1e-9);
  EXPECT_FALSE(h.at(180'000'000 + AttitudeHistory::kMaxExtrapolationNs + 1, &q));
  EXPECT_FALSE(h.at(-1, &q)) << "older than every sample";
}

TEST(Attitude, RefusesSamplesOutOfOrderOrNotFiniteAndForgetsTheOldest) {
  AttitudeHistory h = yawing(0.0, 10'000'000, AttitudeHistory::kCapacity + 5);
  EXPECT_EQ(h.size(), AttitudeHistory::kCapacity);
  Eigen::Quaterniond q;
  EXPECT_FALSE(h.at(4 * 10'000'000, &q)) << "sample 4 was forgotten";
  AttitudeSample late;
  late.t_ns = 0;
  EXPECT_FALSE(h.add(late));
  AttitudeSample broken;
  broken.t_ns = int64_t{10} << 40;
  broken.q_n_b.coeffs() << NAN, 0, 0, 1;
  EXPECT_FALSE(h.add(broken));
  broken.q_n_b.coeffs() << 0, 0, 0, 2;  // not a rotation
  EXPECT_FALSE(h.add(broken));
  AttitudeHistory gap;
  AttitudeSample s;
  ASSERT_TRUE(gap.add(s));
  s.t_ns = 500'000'000;
  ASSERT_TRUE(gap.add(s));
  EXPECT_FALSE(gap.at(250'000'000, &q)) << "a half-second outage says nothing of its middle";
}

TEST(Attitude, ThePriorIsTheBodysTurnSeenFromTheCamera) {
  // A forward camera (optical axis = body front), body yawing right at 3 rad/s.
  SE3 T_b_c(Eigen::Quaterniond((Matrix3d() << 0, 0, 1, 1, 0, 0, 0, 1, 0).finished()),
            Vector3d(0.1, 0, 0));
  const AttitudeHistory h = yawing(3.0, 10'000'000, 20);
  const RotationPrior p = rotation_prior(h, T_b_c, 50'000'000, 83'000'000, 0.2 * kDeg, 0.002);
  ASSERT_TRUE(p.valid);
  // Yaw right about body down is, for the camera, a turn about its own down axis (+y).
  EXPECT_NEAR(angle_between(p.q_c0_c1, turn(Vector3d::UnitY(), 3.0 * 0.033)), 0, 1e-9);
  EXPECT_NEAR(p.sigma_rad, std::hypot(0.2 * kDeg, 3.0 * 0.002), 1e-12);
  EXPECT_FALSE(rotation_prior(h, T_b_c, 50'000'000, 50'000'000, 0, 0).valid);
  EXPECT_FALSE(rotation_prior(h, T_b_c, -10, 50'000'000, 0, 0).valid);
}

TEST(Attitude, TheLevelFrameHasGravityDownAndTheFirstBodysHeading) {
  // A forward camera on a body pitched up 10 degrees, rolled 5, heading 70 degrees.
  const SE3 T_b_c(Eigen::Quaterniond((Matrix3d() << 0, 0, 1, 1, 0, 0, 0, 1, 0).finished()),
                  Vector3d::Zero());
  const Eigen::Quaterniond q_n_b0 = turn(Vector3d::UnitZ(), 70 * kDeg) *
                                    turn(Vector3d::UnitY(), 10 * kDeg) *
                                    turn(Vector3d::UnitX(), 5 * kDeg);
  // At the world's origin (T_w_c = identity) and later, after the camera moved and turned.
  const SE3 T_w_c1(turn(Vector3d(1, 2, 3), 25 * kDeg), Vector3d(0.3, -0.2, 1.0));
  const Eigen::Quaterniond q_b0_b1 =
      T_b_c.quaternion() * T_w_c1.quaternion() * T_b_c.quaternion().conjugate();
  for (const auto& [q_n_b, T_w_c] :
       {std::make_pair(q_n_b0, SE3()),
        std::make_pair(Eigen::Quaterniond(q_n_b0 * q_b0_b1), T_w_c1)}) {
    const Eigen::Quaterniond q_l_w = level_from_world(down_in_world(q_n_b, T_b_c, T_w_c), T_b_c);
    // The level frame's down is the autopilot's down ...
    const Eigen::Quaterniond q_n_w = q_n_b * T_b_c.quaternion() * T_w_c.quaternion().conjugate();
    const Vector3d down_w = q_n_w.conjugate() * Vector3d::UnitZ();
    EXPECT_NEAR((q_l_w * down_w - Vector3d::UnitZ()).norm(), 0, 1e-9);
    // ... and the first body's front, levelled, is its +x.
    const Vector3d front_l = q_l_w * (T_b_c.quaternion().conjugate() * Vector3d::UnitX());
    EXPECT_NEAR(front_l.y(), 0, 1e-9);
    EXPECT_GT(front_l.x(), 0.9);
    EXPECT_NEAR(std::atan2(-front_l.z(), front_l.x()), 10 * kDeg, 1e-9) << "pitched up 10";
  }
}

TEST(Attitude, GravityStandsWhenTenFramesAgreeAndNotWhenTheyDrift) {
  GravityEstimate g;
  Vector3d down;
  const Vector3d truth = Vector3d(0.1, 0.98, -0.05).normalized();
  for (int i = 0; i < GravityEstimate::kFrames; ++i) {
    EXPECT_FALSE(g.agreed(&down)) << "not before ten";
    // 0.3 degrees of noise about alternating axes.
    g.add(so3_exp(Vector3d::Unit(i % 3) * (i % 2 ? 0.3 : -0.3) * kDeg) * truth);
  }
  ASSERT_TRUE(g.agreed(&down));
  EXPECT_LT(std::acos(std::min(1.0, down.dot(truth))), 0.2 * kDeg) << "their mean";
  // A timing error on a turning body: each frame's estimate tilted a little more.
  GravityEstimate drifting;
  for (int i = 0; i < GravityEstimate::kFrames; ++i) {
    drifting.add(so3_exp(Vector3d::UnitX() * (0.4 * i * kDeg)) * truth);
  }
  EXPECT_FALSE(drifting.agreed(&down)) << "3.6 degrees from first to last";
}

}  // namespace
}  // namespace rgbdtam

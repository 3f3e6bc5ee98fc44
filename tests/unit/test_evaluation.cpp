// The TUM metrics on trajectories whose answers are known in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>

#include "rgbdtam/core/evaluation.hpp"
#include "trajectory_plot.hpp"

namespace rgbdtam {
namespace {

std::vector<StampedPose> circle(double t0, double dt, int n, double radius) {
  std::vector<StampedPose> out;
  for (int i = 0; i < n; ++i) {
    const double a = 0.05 * i;
    out.push_back({t0 + i * dt, SE3(so3_exp(Vector3d(0, a, 0)),
                                    Vector3d(radius * std::cos(a), 0.1 * std::sin(3 * a),
                                             radius * std::sin(a)))});
  }
  return out;
}

TEST(Associate, GreedyOneToOneWithinLimit) {
  const std::vector<double> a = {1.00, 1.03, 1.06, 2.00};
  const std::vector<double> b = {1.005, 1.012, 1.061, 2.5};
  const auto m = associate(a, b);
  // 1.00-1.005 (0.005) and 1.06-1.061 (0.001) match; 1.03 is 0.018 from 1.012 and matches it;
  // 2.00 has nothing within 0.02.
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0], std::make_pair(0, 0));
  EXPECT_EQ(m[1], std::make_pair(1, 1));
  EXPECT_EQ(m[2], std::make_pair(2, 2));
  // Each stamp is used once: two candidates for one b, the closer wins.
  const auto m2 = associate({1.0, 1.01}, {1.009});
  ASSERT_EQ(m2.size(), 1u);
  EXPECT_EQ(m2[0].first, 1);
}

TEST(Ate, ZeroForARigidlyMovedCopyAndExactForAConstantOffset) {
  const auto gt = circle(100.0, 0.1, 50, 1.0);
  auto est = gt;
  const SE3 G = SE3::exp((Vector6d() << 0.5, -1, 2, 0.3, 0.2, -0.1).finished());
  for (auto& p : est) p.T_w_c = G * p.T_w_c;
  AteResult r;
  ASSERT_TRUE(evaluate_ate(gt, est, &r));
  EXPECT_EQ(r.compared, 50);
  EXPECT_LT(r.rmse_m, 1e-9);
  // Alternating +-1 cm along one axis cannot be aligned away: RMSE is exactly 1 cm.
  est = gt;
  for (size_t i = 0; i < est.size(); ++i) {
    est[i].T_w_c = SE3(est[i].T_w_c.quaternion(),
                       est[i].T_w_c.translation() + Vector3d(0, 0.01 * (i % 2 ? 1 : -1), 0));
  }
  ASSERT_TRUE(evaluate_ate(gt, est, &r));
  EXPECT_NEAR(r.rmse_m, 0.01, 2e-4);
}

TEST(Ate, UsesOnlyAssociatedPoses) {
  const auto gt = circle(100.0, 0.01, 300, 1.0);
  auto est = circle(100.0, 0.03, 100, 1.0);  // a 30 Hz estimate of a 100 Hz ground truth
  est.push_back({500.0, SE3()});             // no ground truth near it: ignored
  AteResult r;
  ASSERT_TRUE(evaluate_ate(gt, est, &r));
  EXPECT_EQ(r.compared, 100);
  EXPECT_FALSE(evaluate_ate(gt, {{900.0, SE3()}}, &r));
}

TEST(Rpe, ZeroForRigidCopyAndMatchesAKnownDrift) {
  const auto gt = circle(10.0, 0.1, 60, 1.0);
  auto est = gt;
  const SE3 G = SE3::exp((Vector6d() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  for (auto& p : est) p.T_w_c = G * p.T_w_c;
  RpeResult r;
  ASSERT_TRUE(evaluate_rpe(gt, est, 1.0, &r));
  EXPECT_LT(r.trans_rmse_m, 1e-9);
  EXPECT_LT(r.rot_rmse_deg, 1e-6);
  // On a rotation-free path, a drift of 2 cm per 0.1 s along x is 20 cm per second.
  std::vector<StampedPose> line;
  for (int i = 0; i < 60; ++i)
    line.push_back({10.0 + 0.1 * i, SE3(Eigen::Quaterniond::Identity(), Vector3d(0, 0, 0.05 * i))});
  est = line;
  for (size_t i = 0; i < est.size(); ++i) {
    est[i].T_w_c = est[i].T_w_c * SE3(Eigen::Quaterniond::Identity(), Vector3d(0.02 * i, 0, 0));
  }
  ASSERT_TRUE(evaluate_rpe(line, est, 1.0, &r));
  EXPECT_NEAR(r.trans_rmse_m, 0.20, 1e-6);
  // Pairs whose later index is the last estimate are dropped, as in evaluate_rpe.py.
  EXPECT_EQ(r.compared, 50 - 1);
}

TEST(Coverage, CountsFramesWithGroundTruthOnly) {
  const auto gt = circle(0.0, 0.01, 200, 1.0);  // covers 0 .. 1.99 s
  std::vector<double> frames;
  for (int i = 0; i < 80; ++i) frames.push_back(i * 1.0 / 30.0);  // 0 .. 2.63 s
  std::vector<StampedPose> est;
  for (int i = 0; i < 80; i += 2) est.push_back({frames[static_cast<size_t>(i)], SE3()});
  const Coverage c = evaluate_coverage(frames, gt, est);
  EXPECT_EQ(c.frames, 61);     // frames 0 .. 60, up to 1.99 + 0.02 s
  EXPECT_EQ(c.estimated, 31);  // the even ones
  EXPECT_DOUBLE_EQ(c.fraction(), 31.0 / 61.0);
}

// A 100 Hz ground truth moving along z, and 25 Hz estimates of it: with a 0.5 s window, each
// estimate i is compared with estimate i - 12.
std::vector<StampedPose> line_at(double dt, int n) {
  std::vector<StampedPose> out;
  for (int i = 0; i < n; ++i)
    out.push_back(
        {5.0 + dt * i, SE3(Eigen::Quaterniond::Identity(), Vector3d(0, 0, 0.3 * dt * i))});
  return out;
}

TEST(FalseValid, ExactCopyHasNoneAndAJumpCountsWhileInTheWindow) {
  const auto gt = line_at(0.01, 500);
  auto est = line_at(0.04, 100);
  FalseValidResult r = evaluate_false_valid(gt, est);
  EXPECT_EQ(r.checked, 99);
  EXPECT_EQ(r.count, 0);
  EXPECT_LT(r.worst_translation_m, 1e-9);
  // A 12 cm jump at estimate 50: estimates 50..61 still see one from before it.
  for (size_t i = 50; i < est.size(); ++i)
    est[i].T_w_c =
        SE3(est[i].T_w_c.quaternion(), est[i].T_w_c.translation() + Vector3d(0.12, 0, 0));
  r = evaluate_false_valid(gt, est);
  EXPECT_EQ(r.count, 12);
  EXPECT_NEAR(r.worst_translation_m, 0.12, 1e-9);
  EXPECT_DOUBLE_EQ(r.first_stamp_s(), est[50].stamp_s);
  // A 1 s gap: the estimate after it has nothing in its window and is not checked.
  est.erase(est.begin() + 70, est.begin() + 95);
  r = evaluate_false_valid(gt, est);
  EXPECT_EQ(r.checked, 99 - 25 - 1);
  EXPECT_EQ(r.count, 12);
}

// At 10 Hz a pose lies exactly 0.5 s (the window) and 0.1 s (the NEES pairs' gap) before
// others. The stamp of a replay in memory (integer nanoseconds) and of the same pose read back
// from its TUM file round differently; the verdicts must not depend on which.
TEST(FalseValid, IntervalsOfExactlyTheWindowCountWhateverTheStampsRounding) {
  const auto gt = line_at(0.01, 3000);
  std::vector<StampedPose> from_ns, from_text;
  std::vector<Eigen::Matrix<double, 6, 6>> cov;
  for (int i = 0; i < 100; ++i) {
    const int64_t ns = 5'000'000'000 + int64_t{i} * 100'000'000;
    char text[32];
    std::snprintf(text, sizeof(text), "%.6f", static_cast<double>(ns) * 1e-9);
    const SE3 pose(Eigen::Quaterniond::Identity(), Vector3d(0, 0, 0.3 * 0.1 * i));
    from_ns.push_back({static_cast<double>(ns) * 1e-9, pose});
    from_text.push_back({std::strtod(text, nullptr), pose});
    cov.push_back(1e-6 * Eigen::Matrix<double, 6, 6>::Identity());
  }
  EXPECT_EQ(evaluate_false_valid(gt, from_ns).checked, 99);
  EXPECT_EQ(evaluate_false_valid(gt, from_text).checked, 99);
  EXPECT_EQ(evaluate_frame_to_frame_nees(gt, from_ns, cov).pairs, 99);
  EXPECT_EQ(evaluate_frame_to_frame_nees(gt, from_text, cov).pairs, 99);
}

TEST(FalseValid, RotationLimitIsFiveDegrees) {
  const auto gt = line_at(0.01, 500);
  for (const double deg : {4.0, 6.0}) {
    auto est = line_at(0.04, 100);
    const Eigen::Quaterniond turn = so3_exp(Vector3d(0, deg * M_PI / 180.0, 0));
    for (size_t i = 30; i < est.size(); ++i)
      est[i].T_w_c = SE3(turn * est[i].T_w_c.quaternion(), est[i].T_w_c.translation());
    const FalseValidResult r = evaluate_false_valid(gt, est);
    EXPECT_NEAR(r.worst_rotation_deg, deg, 1e-6);
    EXPECT_EQ(r.count, deg > 5.0 ? 12 : 0);
  }
}

TEST(Nees, AveragesSixWhenTheCovarianceIsTrueAndScalesWithIt) {
  // Ground truth at 100 Hz along a curve; estimates at every third sample, each perturbed in
  // its camera frame by noise drawn from C. The frame-to-frame error then has covariance 2C
  // (to first order), which is what the evaluation assumes from the two reported C.
  std::vector<StampedPose> gt, est;
  std::vector<Eigen::Matrix<double, 6, 6>> cov;
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  C.diagonal() << 4e-6, 1e-6, 9e-6, 1e-6, 4e-6, 2.5e-7;  // 1-3 mm, 0.03-0.11 degrees
  C(0, 4) = C(4, 0) = 1e-6;                              // sideways motion and turning, correlated
  const Eigen::Matrix<double, 6, 6> L = C.llt().matrixL();
  std::mt19937 rng(11);
  std::normal_distribution<double> n01;
  for (int i = 0; i < 6000; ++i) {
    const double t = i * 0.01;
    gt.push_back({t, SE3(so3_exp(Vector3d(0.1 * std::sin(t), 0.2 * t, 0)),
                         Vector3d(0.3 * std::sin(0.5 * t), 0.1 * t, 0.05 * std::cos(t)))});
    if (i % 3 != 0) continue;
    Vector6d xi;
    for (int k = 0; k < 6; ++k) xi[k] = n01(rng);
    const Vector6d noise = L * xi;
    const SE3 perturbation(so3_exp(noise.tail<3>()), noise.head<3>());
    est.push_back({t, gt.back().T_w_c * perturbation});
    cov.push_back(C);
  }
  const NeesResult consistent = evaluate_frame_to_frame_nees(gt, est, cov);
  EXPECT_EQ(consistent.pairs, 1999);
  EXPECT_NEAR(consistent.mean, 6.0, 0.6);
  EXPECT_NEAR(consistent.mean_translation, 3.0, 0.4);
  for (auto& c : cov) c *= 4.0;  // four times too cautious: a quarter of the NEES
  EXPECT_NEAR(evaluate_frame_to_frame_nees(gt, est, cov).mean, 1.5, 0.15);
  EXPECT_EQ(consistent.misleading, 0) << "a true covariance misleads about one pose in 10^4";
  EXPECT_GT(consistent.p99, consistent.median);
}

// The camera walking along x at 0.2 m/s while turning at 0.1 rad/s, and an estimate of it
// off_m along its own x.
SE3 walking(double t) { return SE3(so3_exp(Vector3d(0, 0.1 * t, 0)), Vector3d(0.2 * t, 0, 0)); }
SE3 shifted(const SE3& T, double off_m) {
  return T * SE3(Eigen::Quaterniond::Identity(), Vector3d(off_m, 0, 0));
}

TEST(Nees, APoseWrongBeyondItsCovarianceByMoreThanACentimetreIsMisleading) {
  // Exact estimates at 30 Hz with a 1 mm covariance; one pose 5 cm off (its step in and out
  // of it both wrong), another 2 cm off but sent with a 3 cm covariance (honest), and one
  // 1 cm off: outside its region, but by less than a centimetre.
  std::vector<StampedPose> gt, est;
  std::vector<Eigen::Matrix<double, 6, 6>> cov;
  const Eigen::Matrix<double, 6, 6> tight = 1e-6 * Eigen::Matrix<double, 6, 6>::Identity();
  for (int i = 0; i < 90; ++i) {
    const double t = i / 30.0;
    gt.push_back({t, walking(t)});
    const double off = i == 30 ? 0.05 : i == 60 ? 0.02 : i == 75 ? 0.01 : 0.0;
    est.push_back({t, shifted(walking(t), off)});
    cov.push_back(i == 60 ? 9e-4 * Eigen::Matrix<double, 6, 6>::Identity() : tight);
  }
  const NeesResult r = evaluate_frame_to_frame_nees(gt, est, cov);
  ASSERT_EQ(r.misleading, 2) << "the 5 cm pose, and the exact one after it";
  EXPECT_NEAR(r.misleading_stamps_s[0], 1.0, 1e-9);
  EXPECT_NEAR(r.misleading_stamps_s[1], 31 / 30.0, 1e-9);
  EXPECT_GT(r.worst_excess_m, 0.04);
  EXPECT_LT(r.worst_excess_m, 0.05);
}

// A 7.5 Hz camera's consecutive frames are 133 ms apart: they are still compared (a pose 5 cm
// off is misleading there too), while a lost stretch between two estimates is still skipped.
TEST(Nees, ASlowCamerasConsecutiveFramesAreCheckedAndALostStretchIsNot) {
  std::vector<StampedPose> gt, est;
  std::vector<Eigen::Matrix<double, 6, 6>> cov;
  const Eigen::Matrix<double, 6, 6> tight = 1e-6 * Eigen::Matrix<double, 6, 6>::Identity();
  for (int i = 0; i < 40; ++i) {
    const double t = i / 7.5;
    gt.push_back({t, walking(t)});
    if (i >= 20 && i < 24) continue;  // lost
    est.push_back({t, shifted(walking(t), i == 10 ? 0.05 : 0.0)});
    cov.push_back(tight);
  }
  const NeesResult r = evaluate_frame_to_frame_nees(gt, est, cov);
  EXPECT_EQ(r.pairs, static_cast<int>(est.size()) - 2) << "every pair but the one across the loss";
  ASSERT_EQ(r.misleading, 2);
  EXPECT_NEAR(r.misleading_stamps_s[0], 10 / 7.5, 1e-9);
}

}  // namespace
}  // namespace rgbdtam

namespace rgbdtam {
namespace {

// A circle in a tilted plane; the estimate loses frames 40-59 and jumps 30 cm at frame 80.
TEST(TrajectoryPlot, MarksLostStretchesAndFalseValidPosesOnThePrincipalPlane) {
  std::vector<StampedPose> gt, est;
  std::vector<double> frames;
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.7, Vector3d(1, 1, 0).normalized()));
  for (int i = 0; i < 120; ++i) {
    const double t = 10 + i / 30.0, a = i * 0.05;
    frames.push_back(t);
    const SE3 pose(Eigen::Quaterniond::Identity(), tilt * Vector3d(std::cos(a), std::sin(a), 0));
    gt.push_back({t, pose});
    if (i >= 40 && i < 60) continue;
    const Vector3d jump = i == 80 ? Vector3d(0.3, 0, 0) : Vector3d::Zero();
    est.push_back({t, SE3(pose.quaternion(), pose.translation() + jump)});
  }
  const EvaluationReport report = evaluate_all(gt, est, &frames);
  ASSERT_TRUE(report.ate_ok);
  EXPECT_GE(report.false_valid.count, 1);
  EXPECT_EQ(report.false_valid.stamps_s.size(), static_cast<size_t>(report.false_valid.count));
  PlotInput in;
  in.gt = &gt;
  in.est = &est;
  in.frame_stamps = &frames;
  in.report = &report;
  in.title = "circle <test> & tilt";
  const std::vector<LostStretch> lost = lost_stretches(in);
  ASSERT_EQ(lost.size(), 1u);
  EXPECT_DOUBLE_EQ(lost[0].begin_s, frames[40]);
  EXPECT_DOUBLE_EQ(lost[0].end_s, frames[59]);
  // Without the frame list, the gap in the estimate is found by its length.
  in.frame_stamps = nullptr;
  ASSERT_EQ(lost_stretches(in).size(), 1u);
  in.frame_stamps = &frames;

  const std::string svg = trajectory_svg(in);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>\n"), std::string::npos);
  EXPECT_NE(svg.find("circle &lt;test&gt; &amp; tilt"), std::string::npos) << "title escaped";
  auto count = [&](const std::string& what) {
    int n = 0;
    for (size_t at = svg.find(what); at != std::string::npos; at = svg.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("class=\"lost\""), 1);
  // Each false-valid pose in both views.
  EXPECT_EQ(count("class=\"false-valid\""), 2 * report.false_valid.count);
  // The tilted circle seen on its own plane is round: the top view's extent is as wide as high.
  const size_t view = svg.find("<g id=\"top-view\">");
  const size_t line = svg.find("<polyline", view);
  const size_t points = svg.find("points=\"", line) + 8;
  std::istringstream in_points(svg.substr(points, svg.find('"', points) - points));
  double lo_x = 1e9, hi_x = -1e9, lo_y = 1e9, hi_y = -1e9;
  for (std::string xy; in_points >> xy;) {
    const double x = std::stod(xy), y = std::stod(xy.substr(xy.find(',') + 1));
    lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x);
    lo_y = std::min(lo_y, y), hi_y = std::max(hi_y, y);
  }
  EXPECT_NEAR(hi_x - lo_x, hi_y - lo_y, 0.05 * (hi_x - lo_x));
}

// Issue 23, defect 2: one pose at x = 1e300 made the error axis infinite and its tick loop
// endless. The plot ends, small, with no "nan" or "inf" in its numbers.
TEST(TrajectoryPlot, AHostileTrajectoryEndsWithAFinitePlot) {
  std::vector<StampedPose> gt, est;
  for (int i = 0; i < 90; ++i) {
    const double t = i / 30.0;
    gt.push_back({t, SE3(Eigen::Quaterniond::Identity(), Vector3d(0.01 * i, 0, 0))});
    est.push_back(gt.back());
  }
  for (const double absurd : {1e300, 1e200, -1e300}) {
    est[45].T_w_c = SE3(Eigen::Quaterniond::Identity(), Vector3d(absurd, 0, 0));
    const EvaluationReport report = evaluate_all(gt, est, nullptr);
    PlotInput in;
    in.gt = &gt;
    in.est = &est;
    in.report = &report;
    const std::string svg = trajectory_svg(in);
    EXPECT_NE(svg.find("</svg>\n"), std::string::npos) << absurd;
    EXPECT_LT(svg.size(), 64u * 1024) << absurd;
    for (const char* bad : {"nan", "inf,", "inf\""}) {
      EXPECT_EQ(svg.find(bad), std::string::npos) << absurd << ": " << bad;
    }
  }
}

}  // namespace
}  // namespace rgbdtam

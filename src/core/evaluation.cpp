#include "rgbdtam/core/evaluation.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/SVD>

namespace rgbdtam {
namespace {
// TUM files carry stamps to the microsecond: intervals are compared to that, so that a pose
// exactly a window (or a frame period) before another is in it whether its stamp came from a
// file's text or from integer nanoseconds (at 10 Hz, 1000.2 - 1000.1 is 0.1 plus a rounding).
constexpr double kStampResolutionS = 1e-6;
std::vector<double> stamps_of(const std::vector<StampedPose>& t) {
  std::vector<double> s;
  s.reserve(t.size());
  for (const StampedPose& p : t) s.push_back(p.stamp_s);
  return s;
}

double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);  // numpy.median
}

// evaluate_rpe.py's find_closest_index: a bisection that remembers the closest probe.
int find_closest_index(const std::vector<double>& list, double t) {
  int beginning = 0, end = static_cast<int>(list.size()), best = 0;
  double difference = std::fabs(list[0] - t);
  while (beginning < end) {
    const int middle = (end + beginning) / 2;
    if (std::fabs(list[middle] - t) < difference) {
      difference = std::fabs(list[middle] - t);
      best = middle;
    }
    if (t == list[middle]) return middle;
    if (list[middle] > t) {
      end = middle;
    } else {
      beginning = middle + 1;
    }
  }
  return best;
}

double max_gt_gap_s(const std::vector<double>& stamps_gt) {
  std::vector<double> intervals;
  for (size_t i = 1; i < stamps_gt.size(); ++i)
    intervals.push_back(stamps_gt[i] - stamps_gt[i - 1]);
  return 2.0 * median_of(intervals);
}

double rotation_angle_deg(const SE3& e) {
  const double c = std::min(1.0, std::max(-1.0, (e.rotation().trace() - 1.0) / 2.0));
  return std::acos(c) * 180.0 / M_PI;
}
}  // namespace

std::vector<std::pair<int, int>> associate(const std::vector<double>& first,
                                           const std::vector<double>& second, double offset,
                                           double max_difference) {
  struct Candidate {
    double diff;
    int a, b;
  };
  std::vector<Candidate> candidates;
  for (int a = 0; a < static_cast<int>(first.size()); ++a) {
    // second is sorted, so only a window can be within max_difference.
    const double lo = first[a] - offset - max_difference;
    auto it = std::lower_bound(second.begin(), second.end(), lo);
    for (; it != second.end(); ++it) {
      const double diff = std::fabs(first[a] - (*it + offset));
      if (*it + offset > first[a] + max_difference) break;
      if (diff < max_difference)
        candidates.push_back({diff, a, static_cast<int>(it - second.begin())});
    }
  }
  // Python's sort is stable on (diff, a, b) tuples.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    if (x.diff != y.diff) return x.diff < y.diff;
    if (x.a != y.a) return x.a < y.a;
    return x.b < y.b;
  });
  std::vector<char> used_a(first.size(), 0), used_b(second.size(), 0);
  std::vector<std::pair<int, int>> matches;
  for (const Candidate& c : candidates) {
    if (used_a[c.a] || used_b[c.b]) continue;
    used_a[c.a] = used_b[c.b] = 1;
    matches.emplace_back(c.a, c.b);
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

bool evaluate_ate(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est,
                  AteResult* out) {
  // evaluate_ate.py: first_file = ground truth, second_file = estimate.
  const auto matches = associate(stamps_of(gt), stamps_of(est));
  if (matches.size() < 2) return false;
  const int n = static_cast<int>(matches.size());
  Eigen::Matrix3Xd model(3, n), data(3, n);  // model = estimate, data = ground truth
  for (int i = 0; i < n; ++i) {
    model.col(i) = est[matches[i].second].T_w_c.translation();
    data.col(i) = gt[matches[i].first].T_w_c.translation();
  }
  const Vector3d model_mean = model.rowwise().mean();
  const Vector3d data_mean = data.rowwise().mean();
  const Eigen::Matrix3Xd mz = model.colwise() - model_mean;
  const Eigen::Matrix3Xd dz = data.colwise() - data_mean;
  Matrix3d W = Matrix3d::Zero();
  for (int i = 0; i < n; ++i) W += mz.col(i) * dz.col(i).transpose();
  Eigen::JacobiSVD<Matrix3d> svd(W.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3d S = Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  const Matrix3d R = svd.matrixU() * S * svd.matrixV().transpose();
  const Vector3d t = data_mean - R * model_mean;
  std::vector<double> err(static_cast<size_t>(n));
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    err[i] = (R * model.col(i) + t - data.col(i)).norm();
    sum += err[i];
    sum2 += err[i] * err[i];
  }
  out->compared = n;
  out->rmse_m = std::sqrt(sum2 / n);
  out->mean_m = sum / n;
  out->median_m = median_of(err);
  out->std_m = std::sqrt(std::max(0.0, sum2 / n - out->mean_m * out->mean_m));
  out->min_m = *std::min_element(err.begin(), err.end());
  out->max_m = *std::max_element(err.begin(), err.end());
  out->T_gt_est = SE3(Eigen::Quaterniond(R), t);
  return true;
}

bool evaluate_rpe(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est,
                  double delta_s, RpeResult* out) {
  if (gt.size() < 2 || est.size() < 2) return false;
  const std::vector<double> stamps_gt = stamps_of(gt);
  const std::vector<double> stamps_est = stamps_of(est);
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < static_cast<int>(est.size()); ++i) {
    const int j = find_closest_index(stamps_est, stamps_est[i] + delta_s);
    if (j != static_cast<int>(est.size()) - 1) pairs.emplace_back(i, j);
  }
  // The benchmark subsamples beyond 10000 pairs with Python's RNG; sequences here stay below.
  const double max_dt = max_gt_gap_s(stamps_gt);
  std::vector<double> trans, rot;
  for (const auto& [i, j] : pairs) {
    const int g0 = find_closest_index(stamps_gt, stamps_est[i]);
    const int g1 = find_closest_index(stamps_gt, stamps_est[j]);
    if (std::fabs(stamps_gt[g0] - stamps_est[i]) > max_dt ||
        std::fabs(stamps_gt[g1] - stamps_est[j]) > max_dt) {
      continue;
    }
    // ominus(a, b) = a^-1 b; error = ominus(ominus(P_j, P_i), ominus(Q_j, Q_i)).
    const SE3 d_est = est[j].T_w_c.inverse() * est[i].T_w_c;
    const SE3 d_gt = gt[g1].T_w_c.inverse() * gt[g0].T_w_c;
    const SE3 e = d_est.inverse() * d_gt;
    trans.push_back(e.translation().norm());
    rot.push_back(rotation_angle_deg(e));
  }
  if (trans.empty()) return false;
  auto rms = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x * x;
    return std::sqrt(s / v.size());
  };
  auto mean = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s / v.size();
  };
  out->compared = static_cast<int>(trans.size());
  out->trans_rmse_m = rms(trans);
  out->trans_mean_m = mean(trans);
  out->trans_median_m = median_of(trans);
  out->rot_rmse_deg = rms(rot);
  out->rot_mean_deg = mean(rot);
  out->rot_median_deg = median_of(rot);
  return true;
}

Coverage evaluate_coverage(const std::vector<double>& frame_stamps,
                           const std::vector<StampedPose>& gt,
                           const std::vector<StampedPose>& est) {
  Coverage c;
  const std::vector<double> gt_stamps = stamps_of(gt);
  const std::vector<double> est_stamps = stamps_of(est);
  auto has_near = [](const std::vector<double>& sorted, double t) {
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), t);
    const bool after = it != sorted.end() && std::fabs(*it - t) < 0.02;
    const bool before = it != sorted.begin() && std::fabs(*(it - 1) - t) < 0.02;
    return after || before;
  };
  // A frame is estimated when a pose lies within ATE's association window of it and nearer to
  // it than to any other frame: one pose covers one frame, whatever its stamps' rounding.
  std::vector<double> frames = frame_stamps;
  std::sort(frames.begin(), frames.end());
  for (size_t f = 0; f < frames.size(); ++f) {
    const double t = frames[f];
    if (!has_near(gt_stamps, t)) continue;
    ++c.frames;
    if (est_stamps.empty()) continue;
    const int e = find_closest_index(est_stamps, t);
    if (std::fabs(est_stamps[e] - t) < 0.02 &&
        find_closest_index(frames, est_stamps[e]) == static_cast<int>(f)) {
      ++c.estimated;
    }
  }
  return c;
}

FalseValidResult evaluate_false_valid(const std::vector<StampedPose>& gt,
                                      const std::vector<StampedPose>& est,
                                      const FalseValidLimits& limits) {
  FalseValidResult out;
  if (gt.size() < 2 || est.size() < 2) return out;
  const std::vector<double> stamps_gt = stamps_of(gt);
  const double max_dt = max_gt_gap_s(stamps_gt);
  auto gt_near = [&](double t) {
    const int g = find_closest_index(stamps_gt, t);
    return std::fabs(stamps_gt[g] - t) <= max_dt ? g : -1;
  };
  size_t j = 0;
  for (size_t i = 1; i < est.size(); ++i) {
    while (j < i && est[i].stamp_s - est[j].stamp_s > limits.window_s + kStampResolutionS) ++j;
    if (j == i) continue;  // nothing in the window, as after a gap
    const int gi = gt_near(est[i].stamp_s), gj = gt_near(est[j].stamp_s);
    if (gi < 0 || gj < 0) continue;
    const SE3 d_est = est[i].T_w_c.inverse() * est[j].T_w_c;
    const SE3 d_gt = gt[gi].T_w_c.inverse() * gt[gj].T_w_c;
    const SE3 e = d_est.inverse() * d_gt;
    const double trans = e.translation().norm(), rot = rotation_angle_deg(e);
    ++out.checked;
    out.worst_translation_m = std::max(out.worst_translation_m, trans);
    out.worst_rotation_deg = std::max(out.worst_rotation_deg, rot);
    if (trans > limits.max_translation_m || rot > limits.max_rotation_deg) {
      ++out.count;
      out.stamps_s.push_back(est[i].stamp_s);
    }
  }
  return out;
}

bool interpolate_pose(const std::vector<StampedPose>& gt, double t, double max_gap_s, SE3* out) {
  const auto after = std::lower_bound(gt.begin(), gt.end(), t,
                                      [](const StampedPose& p, double s) { return p.stamp_s < s; });
  if (after != gt.end() && after->stamp_s == t) {
    *out = after->T_w_c;
    return true;
  }
  if (after == gt.begin() || after == gt.end()) return false;
  const StampedPose& b = *after;
  const StampedPose& a = *(after - 1);
  if (b.stamp_s - a.stamp_s > max_gap_s) return false;
  const double f = (t - a.stamp_s) / (b.stamp_s - a.stamp_s);
  *out = SE3(a.T_w_c.quaternion().slerp(f, b.T_w_c.quaternion()),
             (1 - f) * a.T_w_c.translation() + f * b.T_w_c.translation());
  return true;
}

NeesResult evaluate_frame_to_frame_nees(const std::vector<StampedPose>& gt,
                                        const std::vector<StampedPose>& est,
                                        const std::vector<Eigen::Matrix<double, 6, 6>>& covariance,
                                        double max_gap_s, const IntegrityLimits& limits) {
  NeesResult out;
  const double max_gt_gap = max_gt_gap_s(stamps_of(gt));
  // A slower camera's consecutive frames are further apart: at 7.5 Hz every pair would be
  // skipped, and no pose checked.
  std::vector<double> intervals;
  for (size_t i = 1; i < est.size(); ++i) intervals.push_back(est[i].stamp_s - est[i - 1].stamp_s);
  max_gap_s = std::max(max_gap_s, 1.5 * median_of(intervals));
  std::vector<double> nees;
  double sum_t = 0, sum_r = 0;
  for (size_t i = 1; i < est.size() && i < covariance.size(); ++i) {
    if (est[i].stamp_s - est[i - 1].stamp_s > max_gap_s + kStampResolutionS) continue;
    SE3 gt_prev, gt_now;
    if (!interpolate_pose(gt, est[i - 1].stamp_s, max_gt_gap, &gt_prev) ||
        !interpolate_pose(gt, est[i].stamp_s, max_gt_gap, &gt_now)) {
      continue;
    }
    const SE3 d_est = est[i - 1].T_w_c.inverse() * est[i].T_w_c;
    const SE3 d_gt = gt_prev.inverse() * gt_now;
    const Vector3d e_t = (d_gt.inverse() * d_est).translation();
    const Vector3d e_r = so3_log((d_gt.inverse() * d_est).quaternion());
    Vector6d e;
    e << e_t, e_r;
    const Eigen::Matrix<double, 6, 6> c = covariance[i - 1] + covariance[i];
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(c);
    if (ldlt.info() != Eigen::Success || !c.allFinite()) continue;
    nees.push_back(e.dot(ldlt.solve(e)));
    sum_t += e_t.dot(c.topLeftCorner<3, 3>().ldlt().solve(e_t));
    sum_r += e_r.dot(c.bottomRightCorner<3, 3>().ldlt().solve(e_r));
    // Against the reported covariance with the ground truth's own noise.
    Vector6d gt_variance;
    gt_variance << Vector3d::Constant(limits.gt_translation_sigma_m *
                                      limits.gt_translation_sigma_m),
        Vector3d::Constant(limits.gt_rotation_sigma_rad * limits.gt_rotation_sigma_rad);
    const Eigen::Matrix<double, 6, 6> c_gt =
        c + Eigen::Matrix<double, 6, 6>(gt_variance.asDiagonal());
    const double d2 = e.dot(c_gt.ldlt().solve(e));
    if (d2 > limits.chi2_99_99) {
      const Vector6d excess = e * (1.0 - std::sqrt(limits.chi2_99_99 / d2));
      const double excess_m = excess.head<3>().norm(), excess_rad = excess.tail<3>().norm();
      if (excess_m > limits.max_excess_m || excess_rad > limits.max_excess_rad) {
        ++out.misleading;
        out.misleading_stamps_s.push_back(est[i].stamp_s);
        out.worst_excess_m = std::max(out.worst_excess_m, excess_m);
        out.worst_excess_deg = std::max(out.worst_excess_deg, excess_rad * 180.0 / M_PI);
      }
    }
  }
  out.pairs = static_cast<int>(nees.size());
  if (out.pairs == 0) return out;
  double sum = 0;
  for (double v : nees) sum += v;
  out.mean = sum / out.pairs;
  out.mean_translation = sum_t / out.pairs;
  out.mean_rotation = sum_r / out.pairs;
  out.median = median_of(nees);
  std::sort(nees.begin(), nees.end());
  out.p99 = nees[std::min(nees.size() - 1, static_cast<size_t>(0.99 * nees.size()))];
  return out;
}

}  // namespace rgbdtam

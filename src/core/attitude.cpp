#include "rgbdtam/core/attitude.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdtam {

Eigen::Quaterniond quaternion_from_yaw_pitch_roll(double yaw_rad, double pitch_rad,
                                                  double roll_rad) {
  return Eigen::AngleAxisd(yaw_rad, Vector3d::UnitZ()) *
         Eigen::AngleAxisd(pitch_rad, Vector3d::UnitY()) *
         Eigen::AngleAxisd(roll_rad, Vector3d::UnitX());
}
namespace {
// Two samples further apart than this (a link outage) do not describe the motion between them.
constexpr int64_t kMaxGapNs = 100'000'000;
}  // namespace

bool AttitudeHistory::add(const AttitudeSample& s) {
  if (!s.q_n_b.coeffs().allFinite() || !s.rate_b_rad_s.allFinite() ||
      std::abs(s.q_n_b.norm() - 1.0) > 0.01) {
    return false;
  }
  if (size_ > 0 && s.t_ns <= nth(size_ - 1).t_ns) return false;
  if (size_ == kCapacity) {
    first_ = (first_ + 1) % kCapacity;
    --size_;
  }
  AttitudeSample& slot = ring_[(first_ + size_) % kCapacity];
  slot = s;
  slot.q_n_b.normalize();
  ++size_;
  return true;
}

int AttitudeHistory::upper_bound(int64_t t_ns) const {
  int lo = 0, hi = size_;
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (nth(mid).t_ns <= t_ns) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo;
}

bool AttitudeHistory::at(int64_t t_ns, Eigen::Quaterniond* q_n_b) const {
  const int next = upper_bound(t_ns);
  if (next == 0) return false;  // older than every sample
  const AttitudeSample& before = nth(next - 1);
  if (next == size_) {
    const int64_t ahead = t_ns - before.t_ns;
    if (ahead > kMaxExtrapolationNs) return false;
    *q_n_b = before.q_n_b * so3_exp(before.rate_b_rad_s * (static_cast<double>(ahead) * 1e-9));
    return true;
  }
  const AttitudeSample& after = nth(next);
  if (after.t_ns - before.t_ns > kMaxGapNs) return false;
  const double s = static_cast<double>(t_ns - before.t_ns) / (after.t_ns - before.t_ns);
  *q_n_b = before.q_n_b.slerp(s, after.q_n_b);
  return true;
}

double AttitudeHistory::rate_near(int64_t t_ns) const {
  const int next = upper_bound(t_ns);
  double rate = 0;
  for (int i = std::max(0, next - 1); i < std::min(size_, next + 1); ++i) {
    rate = std::max(rate, nth(i).rate_b_rad_s.norm());
  }
  return rate;
}

RotationPrior rotation_prior(const AttitudeHistory& history, const SE3& T_b_c, int64_t from_ns,
                             int64_t to_ns, double attitude_sigma_rad, double timing_sigma_s) {
  RotationPrior prior;
  Eigen::Quaterniond q0, q1;
  if (to_ns <= from_ns || !history.at(from_ns, &q0) || !history.at(to_ns, &q1)) return prior;
  const Eigen::Quaterniond& q_b_c = T_b_c.quaternion();
  prior.valid = true;
  prior.from_ns = from_ns;
  prior.to_ns = to_ns;
  prior.q_c0_c1 = (q_b_c.conjugate() * (q0.conjugate() * q1) * q_b_c).normalized();
  const double rate = std::max(history.rate_near(from_ns), history.rate_near(to_ns));
  prior.sigma_rad = std::hypot(attitude_sigma_rad, rate * timing_sigma_s);
  return prior;
}

Vector3d down_in_world(const Eigen::Quaterniond& q_n_b, const SE3& T_b_c, const SE3& T_w_c) {
  const Eigen::Quaterniond q_n_w = q_n_b * T_b_c.quaternion() * T_w_c.quaternion().conjugate();
  return (q_n_w.conjugate() * Vector3d::UnitZ()).normalized();
}

Eigen::Quaterniond level_from_world(const Vector3d& down_w, const SE3& T_b_c) {
  // The body at the world's origin is the camera there turned by the mounting: R_w_b0 = R_c_b.
  const Vector3d forward_w = T_b_c.quaternion().conjugate() * Vector3d::UnitX();
  const Vector3d z = down_w.normalized();
  const Vector3d x = (forward_w - forward_w.dot(z) * z).normalized();
  Matrix3d R_w_l;
  R_w_l << x, z.cross(x), z;
  return Eigen::Quaterniond(R_w_l.transpose()).normalized();
}

void GravityEstimate::add(const Vector3d& down_w) {
  last_[next_] = down_w;
  next_ = (next_ + 1) % kFrames;
  size_ = std::min(size_ + 1, kFrames);
}

bool GravityEstimate::agreed(Vector3d* down_w) const {
  if (size_ < kFrames) return false;
  Vector3d mean = Vector3d::Zero();
  for (const Vector3d& d : last_) mean += d;
  mean.normalize();
  for (const Vector3d& d : last_) {
    if (std::acos(std::min(1.0, d.dot(mean))) > kAgreeRad) return false;
  }
  *down_w = mean;
  return true;
}

double angle_between(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return so3_log(a.conjugate() * b).norm();
}

}  // namespace rgbdtam

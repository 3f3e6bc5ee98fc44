#include "rgbdtam/core/se3.hpp"

#include <cmath>

namespace rgbdtam {
namespace {
// Below this angle the series expansions are exact to double precision.
constexpr double kSmallAngle = 1e-8;
}  // namespace

Eigen::Quaterniond so3_exp(const Vector3d& omega) {
  const double theta = omega.norm();
  const double half = 0.5 * theta;
  double imag_factor;
  double real;
  if (theta < kSmallAngle) {
    imag_factor = 0.5 - theta * theta / 48.0;
    real = 1.0 - theta * theta / 8.0;
  } else {
    imag_factor = std::sin(half) / theta;
    real = std::cos(half);
  }
  return Eigen::Quaterniond(real, imag_factor * omega.x(), imag_factor * omega.y(),
                            imag_factor * omega.z());
}

Vector3d so3_log(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // shortest rotation
  const double n = q.vec().norm();
  if (n < kSmallAngle) return 2.0 * q.vec() / q.w();
  const double theta = 2.0 * std::atan2(n, q.w());
  return theta / n * q.vec();
}

namespace {
// Left Jacobian V of SO(3): t = V * v in exp(v, omega).
Matrix3d so3_left_jacobian(const Vector3d& omega) {
  const double theta = omega.norm();
  const Matrix3d w = hat(omega);
  if (theta < 1e-5) return Matrix3d::Identity() + 0.5 * w + w * w / 6.0;
  const double t2 = theta * theta;
  return Matrix3d::Identity() + (1.0 - std::cos(theta)) / t2 * w +
         (theta - std::sin(theta)) / (t2 * theta) * w * w;
}
}  // namespace

SE3 SE3::exp(const Vector6d& xi) {
  const Vector3d v = xi.head<3>();
  const Vector3d omega = xi.tail<3>();
  return SE3(so3_exp(omega), so3_left_jacobian(omega) * v);
}

Vector6d SE3::log() const {
  const Vector3d omega = so3_log(q_);
  Vector6d xi;
  xi.head<3>() = so3_left_jacobian(omega).inverse() * t_;
  xi.tail<3>() = omega;
  return xi;
}

Matrix6d adjoint(const SE3& T) {
  Matrix6d A = Matrix6d::Zero();
  const Matrix3d R = T.rotation();
  A.topLeftCorner<3, 3>() = R;
  A.topRightCorner<3, 3>() = hat(T.translation()) * R;
  A.bottomRightCorner<3, 3>() = R;
  return A;
}

}  // namespace rgbdtam

#pragma once
// Rigid transforms T_a_b ("a from b"): p_a = T_a_b * p_b. Twists are ordered (v, omega):
// translation first, rotation second, matching the tracker's Jacobian columns.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rgbdtam {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix3d = Eigen::Matrix3d;
using Vector3d = Eigen::Vector3d;

// [w]x, the cross-product matrix.
inline Matrix3d hat(const Vector3d& w) {
  Matrix3d m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

Eigen::Quaterniond so3_exp(const Vector3d& omega);
Vector3d so3_log(const Eigen::Quaterniond& q);

class SE3 {
 public:
  SE3() : q_(Eigen::Quaterniond::Identity()), t_(Vector3d::Zero()) {}
  SE3(const Eigen::Quaterniond& q, const Vector3d& t) : q_(q.normalized()), t_(t) {}

  static SE3 exp(const Vector6d& xi);
  Vector6d log() const;

  SE3 inverse() const {
    const Eigen::Quaterniond qi = q_.conjugate();
    return SE3(qi, -(qi * t_));
  }
  SE3 operator*(const SE3& o) const { return SE3(q_ * o.q_, q_ * o.t_ + t_); }
  Vector3d operator*(const Vector3d& p) const { return q_ * p + t_; }

  const Eigen::Quaterniond& quaternion() const { return q_; }
  const Vector3d& translation() const { return t_; }
  Matrix3d rotation() const { return q_.toRotationMatrix(); }
  Eigen::Matrix4d matrix() const {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = rotation();
    m.topRightCorner<3, 1>() = t_;
    return m;
  }

 private:
  Eigen::Quaterniond q_;
  Vector3d t_;
};

// The adjoint of T for twists ordered (v, omega): T exp(xi) T^-1 = exp(Ad(T) xi).
Matrix6d adjoint(const SE3& T);

// Whether the motion d moves by at most max_m and turns by at most max_rad.
inline bool within(const SE3& d, double max_m, double max_rad) {
  return d.translation().norm() <= max_m && so3_log(d.quaternion()).norm() <= max_rad;
}

// One number for how far apart two poses are (d maps one to the other), to rank keyframes by:
// a radian of turn counts as 0.3 m of travel.
inline double ranking_distance_m(const SE3& d) {
  constexpr double kMetresPerRadian = 0.3;
  return d.translation().norm() + kMetresPerRadian * so3_log(d.quaternion()).norm();
}

}  // namespace rgbdtam

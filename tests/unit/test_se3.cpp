// Lie-group properties of SE3/SO3, tested the way Sophus tests its own types.
#include <gtest/gtest.h>

#include <cmath>

#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {
namespace {

std::vector<Vector6d> sample_twists() {
  std::vector<Vector6d> out;
  Vector6d xi;
  xi << 0, 0, 0, 0, 0, 0;
  out.push_back(xi);
  xi << 0.1, -0.2, 0.3, 1e-10, -2e-10, 0;
  out.push_back(xi);  // below the small-angle threshold
  xi << 1.0, 2.0, -0.5, 0.3, -0.2, 0.1;
  out.push_back(xi);
  xi << -0.4, 0.0, 2.0, 0.0, 0.0, 3.0;
  out.push_back(xi);  // close to pi
  xi << 0.5, 0.5, 0.5, 1.5, -1.0, 0.7;
  out.push_back(xi);
  return out;
}

TEST(SE3, ExpLogRoundTrip) {
  for (const Vector6d& xi : sample_twists()) {
    EXPECT_LT((SE3::exp(xi).log() - xi).norm(), 1e-9) << xi.transpose();
  }
}

TEST(SE3, InverseAndComposition) {
  const auto twists = sample_twists();
  for (const Vector6d& a : twists) {
    const SE3 A = SE3::exp(a);
    EXPECT_LT((A * A.inverse()).log().norm(), 1e-12);
    EXPECT_LT((A.matrix() * A.inverse().matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
    for (const Vector6d& b : twists) {
      const SE3 B = SE3::exp(b);
      EXPECT_LT(((A * B).matrix() - A.matrix() * B.matrix()).norm(), 1e-12);
      const Vector3d p(0.3, -1.2, 2.5);
      EXPECT_LT(((A * B) * p - A * (B * p)).norm(), 1e-12);
    }
  }
}

TEST(SE3, ExpMatchesMatrixExponential) {
  // exp of the 4x4 twist matrix by a long Taylor series.
  for (const Vector6d& xi : sample_twists()) {
    Eigen::Matrix4d X = Eigen::Matrix4d::Zero();
    X.topLeftCorner<3, 3>() = hat(xi.tail<3>());
    X.topRightCorner<3, 1>() = xi.head<3>();
    Eigen::Matrix4d sum = Eigen::Matrix4d::Identity(), term = Eigen::Matrix4d::Identity();
    for (int k = 1; k < 40; ++k) {
      term = term * X / k;
      sum += term;
    }
    EXPECT_LT((SE3::exp(xi).matrix() - sum).norm(), 1e-10);
  }
}

TEST(SO3, ExpMatchesAngleAxis) {
  const Vector3d w(0.3, -0.7, 1.1);
  const Eigen::AngleAxisd aa(w.norm(), w.normalized());
  EXPECT_LT((so3_exp(w).toRotationMatrix() - aa.toRotationMatrix()).norm(), 1e-12);
  EXPECT_LT((so3_log(so3_exp(w)) - w).norm(), 1e-12);
}

TEST(SE3, LeftPerturbationDerivative) {
  // d/d(delta) of exp(delta) * p at 0 is [I, -[p]x]: the basis of every tracker Jacobian.
  const Vector3d p(0.4, -0.3, 1.7);
  const double h = 1e-7;
  for (int j = 0; j < 6; ++j) {
    Vector6d d = Vector6d::Zero();
    d[j] = h;
    const Vector3d numeric = (SE3::exp(d) * p - SE3::exp(-d) * p) / (2 * h);
    Eigen::Matrix<double, 3, 6> analytic;
    analytic.leftCols<3>() = Matrix3d::Identity();
    analytic.rightCols<3>() = -hat(p);
    EXPECT_LT((numeric - analytic.col(j)).norm(), 1e-7) << "column " << j;
  }
}

}  // namespace
}  // namespace rgbdtam

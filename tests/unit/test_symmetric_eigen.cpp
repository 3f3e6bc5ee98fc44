// Small symmetric eigenproblems: checked against matrices built from known eigenvalues and
// eigenvectors, and by their defining equations.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/core/symmetric_eigen.hpp"
#include "rgbdtam/core/xorshift.hpp"

namespace rgbdtam {
namespace {

// An orthonormal basis from uniform random columns (modified Gram-Schmidt).
template <int N>
Eigen::Matrix<double, N, N> random_rotation(uint32_t seed) {
  Eigen::Matrix<double, N, N> q;
  for (int c = 0; c < N; ++c) {
    for (int r = 0; r < N; ++r) q(r, c) = xorshift32(&seed) / 2147483648.0 - 1.0;
    for (int k = 0; k < c; ++k) q.col(c) -= q.col(k).dot(q.col(c)) * q.col(k);
    q.col(c).normalize();
  }
  return q;
}

// Known, distinct eigenvalues spread over `decades` decades, in a random basis.
template <int N>
void expect_recovers(uint32_t seed, double decades) {
  SCOPED_TRACE(::testing::Message() << N << "x" << N << ", seed " << seed);
  Eigen::Matrix<double, N, 1> lambda;
  for (int i = 0; i < N; ++i) lambda(i) = std::pow(10.0, decades * (i - N / 2) / N) * (i + 1);
  const Eigen::Matrix<double, N, N> q = random_rotation<N>(seed);
  const Eigen::Matrix<double, N, N> a = q * lambda.asDiagonal() * q.transpose();
  const SymmetricEigen<N> e = symmetric_eigen(a);
  const double tolerance = 1e-13 * lambda.cwiseAbs().maxCoeff();
  for (int i = 0; i < N; ++i) {
    EXPECT_NEAR(e.values(i), lambda(i), tolerance) << i;
    if (i > 0) {
      EXPECT_LE(e.values(i - 1), e.values(i));
    }
    // Each eigenvector satisfies its equation and is the known one, up to its sign.
    EXPECT_LT((a * e.vectors.col(i) - e.values(i) * e.vectors.col(i)).norm(), 4 * tolerance);
    EXPECT_NEAR(std::fabs(e.vectors.col(i).dot(q.col(i))), 1.0, 1e-9) << i;
  }
  EXPECT_LT((e.vectors.transpose() * e.vectors - Eigen::Matrix<double, N, N>::Identity()).norm(),
            1e-14 * N);
}

TEST(SymmetricEigen, RecoversKnownEigenvaluesAndVectorsOverTwelveDecades) {
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    expect_recovers<3>(seed, 0.0);
    expect_recovers<3>(seed, 12.0);
    expect_recovers<4>(seed, 3.0);
    expect_recovers<6>(seed, 6.0);
    expect_recovers<6>(seed, 12.0);  // a plane's depth information: condition 1e12
  }
}

TEST(SymmetricEigen, ReadsTheLowerTriangle) {
  Eigen::Matrix3d a;
  a << 2.0, 99.0, 99.0,  //
      1.0, 2.0, 99.0,    //
      0.0, 0.0, 5.0;
  const SymmetricEigen<3> e = symmetric_eigen(a);
  EXPECT_NEAR(e.values(0), 1.0, 1e-15);
  EXPECT_NEAR(e.values(1), 3.0, 1e-15);
  EXPECT_NEAR(e.values(2), 5.0, 1e-15);
  EXPECT_NEAR(std::fabs(e.vectors(2, 2)), 1.0, 1e-15);
}

TEST(SymmetricEigen, EntriesFarFromOneNeitherOverflowNorUnderflow) {
  // Squared, 1e200 overflows and 1e-200 underflows; the solver works on a scaled copy.
  for (const double scale : {1e200, 1e-200}) {
    const Eigen::Vector4d lambda(-1.0, 0.5, 2.0, 3.0);
    const Eigen::Matrix4d q = random_rotation<4>(7);
    const Eigen::Matrix4d a = q * (scale * lambda).asDiagonal() * q.transpose();
    const SymmetricEigen<4> e = symmetric_eigen(a);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(e.values(i) / scale, lambda(i), 1e-13) << scale;
  }
  const SymmetricEigen<3> zero = symmetric_eigen(Eigen::Matrix3d::Zero().eval());
  EXPECT_EQ(zero.values, Eigen::Vector3d::Zero());
  EXPECT_EQ(zero.vectors, Eigen::Matrix3d::Identity());
}

TEST(SymmetricEigen, RepeatedEigenvaluesGiveAnOrthonormalBasisOfTheirSpace) {
  // Rank one: u u^T has eigenvalue |u|^2 along u and 0 on the plane normal to it.
  const Eigen::Vector4d u(1.0, -2.0, 0.5, 3.0);
  const SymmetricEigen<4> e = symmetric_eigen(Eigen::Matrix4d(u * u.transpose()));
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(e.values(i), 0.0, 1e-14 * u.squaredNorm());
    EXPECT_NEAR(e.vectors.col(i).dot(u), 0.0, 1e-14 * u.norm());
  }
  EXPECT_NEAR(e.values(3), u.squaredNorm(), 1e-14 * u.squaredNorm());
  EXPECT_LT((e.vectors.transpose() * e.vectors - Eigen::Matrix4d::Identity()).norm(), 1e-14);
  const SymmetricEigen<6> identity = symmetric_eigen(Matrix6d::Identity().eval());
  EXPECT_EQ(identity.values, (Eigen::Matrix<double, 6, 1>::Ones()));
  EXPECT_EQ(identity.vectors, (Eigen::Matrix<double, 6, 6>::Identity()));
}

TEST(SymmetricEigen, NonFiniteInputGivesNaN) {
  Matrix6d a = Matrix6d::Identity();
  a(4, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(symmetric_eigen(a).values.array().isNaN().all());
  EXPECT_TRUE(symmetric_eigen(a).vectors.array().isNaN().all());
  a(4, 1) = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(symmetric_eigen(a).values.array().isNaN().all());
}

}  // namespace
}  // namespace rgbdtam

#include "rgbdtam/core/symmetric_eigen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace rgbdtam {
namespace {
constexpr int kMaxSize = 6;
// Cyclic sweeps converge quadratically: a 6x6 needs fewer than 10.
constexpr int kMaxSweeps = 50;

// a: n x n column-major, symmetric from its lower triangle; overwritten. values ascending,
// vectors column-major, column i for values[i]; all NaN for a non-finite a.
void jacobi(double* a, int n, double* values, double* vectors) {
  auto A = [&](int r, int c) -> double& { return a[c * n + r]; };
  auto V = [&](int r, int c) -> double& { return vectors[c * n + r]; };
  // Scaled to entries of at most 1, as Eigen's solver does: sums of squares neither overflow
  // nor underflow.
  double max_abs = 0.0;
  bool finite = true;
  for (int c = 0; c < n; ++c) {
    for (int r = c; r < n; ++r) {
      finite = finite && std::isfinite(A(r, c));
      max_abs = std::max(max_abs, std::fabs(A(r, c)));
    }
  }
  if (!finite) {
    std::fill(values, values + n, std::numeric_limits<double>::quiet_NaN());
    std::fill(vectors, vectors + n * n, std::numeric_limits<double>::quiet_NaN());
    return;
  }
  const double unit = max_abs > 0.0 ? 1.0 / max_abs : 1.0;
  double sum_sq = 0.0;
  for (int c = 0; c < n; ++c) {
    for (int r = 0; r < n; ++r) {
      A(r, c) = r < c ? A(c, r) : A(r, c) * unit;  // the lower triangle's, scaled already
      V(r, c) = r == c ? 1.0 : 0.0;
      sum_sq += A(r, c) * A(r, c);
    }
  }
  const double tiny =
      sum_sq * std::numeric_limits<double>::epsilon() * std::numeric_limits<double>::epsilon();
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    double off = 0.0;
    for (int q = 1; q < n; ++q)
      for (int p = 0; p < q; ++p) off += A(p, q) * A(p, q);
    if (!(off > tiny)) break;
    for (int q = 1; q < n; ++q) {
      for (int p = 0; p < q; ++p) {
        if (A(p, q) == 0.0) continue;
        // The rotation in the (p, q) plane that zeroes A(p, q) (Golub and Van Loan, 8.5.2),
        // the smaller of the two angles.
        const double tau = (A(q, q) - A(p, p)) / (2.0 * A(p, q));
        const double t = (tau >= 0.0 ? 1.0 : -1.0) / (std::fabs(tau) + std::hypot(1.0, tau));
        const double c = 1.0 / std::sqrt(1.0 + t * t), s = t * c;
        for (int k = 0; k < n; ++k) {  // A J
          const double kp = A(k, p), kq = A(k, q);
          A(k, p) = c * kp - s * kq;
          A(k, q) = s * kp + c * kq;
        }
        for (int k = 0; k < n; ++k) {  // J^T (A J)
          const double pk = A(p, k), qk = A(q, k);
          A(p, k) = c * pk - s * qk;
          A(q, k) = s * pk + c * qk;
        }
        for (int k = 0; k < n; ++k) {  // V J
          const double kp = V(k, p), kq = V(k, q);
          V(k, p) = c * kp - s * kq;
          V(k, q) = s * kp + c * kq;
        }
      }
    }
  }
  for (int i = 0; i < n; ++i) values[i] = A(i, i) * max_abs;
  // Insertion sort, ascending, the vectors with their values.
  for (int i = 1; i < n; ++i) {
    for (int j = i; j > 0 && values[j] < values[j - 1]; --j) {
      std::swap(values[j], values[j - 1]);
      for (int k = 0; k < n; ++k) std::swap(V(k, j), V(k, j - 1));
    }
  }
}

template <int N>
SymmetricEigen<N> solve(const Eigen::Matrix<double, N, N>& a) {
  static_assert(N <= kMaxSize, "for small matrices");
  Eigen::Matrix<double, N, N> work = a;
  SymmetricEigen<N> out;
  jacobi(work.data(), N, out.values.data(), out.vectors.data());
  return out;
}
}  // namespace

SymmetricEigen<3> symmetric_eigen(const Eigen::Matrix<double, 3, 3>& a) { return solve<3>(a); }
SymmetricEigen<4> symmetric_eigen(const Eigen::Matrix<double, 4, 4>& a) { return solve<4>(a); }
SymmetricEigen<6> symmetric_eigen(const Eigen::Matrix<double, 6, 6>& a) { return solve<6>(a); }

}  // namespace rgbdtam

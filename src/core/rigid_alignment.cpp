#include "rgbdtam/core/rigid_alignment.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdtam/core/symmetric_eigen.hpp"
#include "rgbdtam/core/xorshift.hpp"

namespace rgbdtam {
namespace {
double threshold_m(const PointPair& p, const RigidRansacOptions& opt) {
  const double z = std::max(p.a.z(), p.b.z());
  return std::max(opt.min_threshold_m, opt.sigmas * opt.inverse_depth_sigma * z * z);
}

int count_inliers(const PointPair* pairs, int n, const SE3& T_b_a, const RigidRansacOptions& opt,
                  uint8_t* inlier, double* sum_sq) {
  int count = 0;
  *sum_sq = 0.0;
  for (int i = 0; i < n; ++i) {
    const double e = (pairs[i].b - T_b_a * pairs[i].a).norm();
    const bool in = e < threshold_m(pairs[i], opt);
    if (inlier != nullptr) inlier[i] = in;
    if (in) ++count, *sum_sq += e * e;
  }
  return count;
}
}  // namespace

bool horn_alignment(const PointPair* pairs, int n, const uint8_t* use, SE3* T_b_a) {
  Vector3d ca = Vector3d::Zero(), cb = Vector3d::Zero();
  int m = 0;
  for (int i = 0; i < n; ++i) {
    if (use != nullptr && use[i] == 0) continue;
    ca += pairs[i].a;
    cb += pairs[i].b;
    ++m;
  }
  if (m < 3) return false;
  ca /= m;
  cb /= m;
  Matrix3d S = Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    if (use != nullptr && use[i] == 0) continue;
    S += (pairs[i].a - ca) * (pairs[i].b - cb).transpose();
  }
  const double xx = S(0, 0), xy = S(0, 1), xz = S(0, 2), yx = S(1, 0), yy = S(1, 1), yz = S(1, 2),
               zx = S(2, 0), zy = S(2, 1), zz = S(2, 2);
  Eigen::Matrix4d N;
  N << xx + yy + zz, yz - zy, zx - xz, xy - yx,  //
      yz - zy, xx - yy - zz, xy + yx, zx + xz,   //
      zx - xz, xy + yx, -xx + yy - zz, yz + zy,  //
      xy - yx, zx + xz, yz + zy, -xx - yy + zz;
  const SymmetricEigen<4> eig = symmetric_eigen(N);
  // Collinear or coincident points leave the rotation undetermined: the two largest
  // eigenvalues of N coincide.
  const Eigen::Vector4d& lambda = eig.values;
  if (!(lambda(3) - lambda(2) > 1e-9 * std::max(1.0, std::fabs(lambda(3))))) return false;
  const Eigen::Vector4d q = eig.vectors.col(3);
  const Eigen::Quaterniond R(q(0), q(1), q(2), q(3));
  *T_b_a = SE3(R, cb - R.normalized() * ca);
  return true;
}

RigidRansacResult rigid_ransac(const PointPair* pairs, int n, const RigidRansacOptions& opt,
                               uint8_t* inlier) {
  RigidRansacResult best;
  if (n < 3) {
    std::fill(inlier, inlier + n, uint8_t{0});
    return best;
  }
  uint32_t seed = opt.seed == 0 ? 1u : opt.seed;
  double sum_sq = 0.0;
  for (int it = 0; it < opt.iterations; ++it) {
    PointPair sample[3];
    const int i0 = static_cast<int>(xorshift32(&seed) % n);
    const int i1 = static_cast<int>(xorshift32(&seed) % n);
    const int i2 = static_cast<int>(xorshift32(&seed) % n);
    if (i0 == i1 || i1 == i2 || i0 == i2) continue;
    sample[0] = pairs[i0], sample[1] = pairs[i1], sample[2] = pairs[i2];
    SE3 T;
    if (!horn_alignment(sample, 3, nullptr, &T)) continue;
    const int count = count_inliers(pairs, n, T, opt, nullptr, &sum_sq);
    if (count > best.inliers) best.inliers = count, best.T_b_a = T;
  }
  if (best.inliers < 3) {
    std::fill(inlier, inlier + n, uint8_t{0});
    best.inliers = 0;
    return best;
  }
  // Refit on the inliers, twice: the refit's own inliers are the answer.
  for (int refit = 0; refit < 2; ++refit) {
    count_inliers(pairs, n, best.T_b_a, opt, inlier, &sum_sq);
    SE3 T;
    if (!horn_alignment(pairs, n, inlier, &T)) break;
    best.T_b_a = T;
  }
  best.inliers = count_inliers(pairs, n, best.T_b_a, opt, inlier, &sum_sq);
  best.rms_m = best.inliers > 0 ? std::sqrt(sum_sq / best.inliers) : 0.0;
  return best;
}

}  // namespace rgbdtam

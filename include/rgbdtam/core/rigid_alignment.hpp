#pragma once
// Rigid alignment of 3-D point pairs: Horn's closed form (unit quaternions, 1987) inside a
// RANSAC loop. Used to verify place matches: descriptor matches lifted to 3-D by each view's
// depth must agree on one rigid motion. Deterministic (fixed-seed sampling); never allocates.

#include <cstdint>

#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

struct PointPair {
  Vector3d a, b;  // the same point in frame A and in frame B, m
};

// T_b_a minimising sum |b - T a|^2 over pairs[i] with use[i] != 0 (all when use is null).
// Needs three pairs that are not collinear; returns false otherwise.
bool horn_alignment(const PointPair* pairs, int n, const uint8_t* use, SE3* T_b_a);

struct RigidRansacOptions {
  int iterations = 300;
  // A pair is an inlier within max(min_threshold_m, sigmas * sigma_rho * z^2) of the
  // motion: structured-light depth error grows with the square of depth (sigma_rho, 1/m).
  double min_threshold_m = 0.03;
  double sigmas = 3.0;
  double inverse_depth_sigma = 0.01;
  uint32_t seed = 1;
};

struct RigidRansacResult {
  SE3 T_b_a;
  int inliers = 0;
  double rms_m = 0.0;  // of the inliers, after the refit
};

// inlier (size n) receives the refit's inliers. inliers = 0 when nothing fits.
RigidRansacResult rigid_ransac(const PointPair* pairs, int n, const RigidRansacOptions& opt,
                               uint8_t* inlier);

}  // namespace rgbdtam

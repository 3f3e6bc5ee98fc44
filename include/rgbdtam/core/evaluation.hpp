#pragma once
// The TUM RGB-D benchmark's metrics, reproduced exactly: associate.py (greedy one-to-one,
// |dt| < 0.02 s), evaluate_ate.py (Horn alignment without scale, RMSE of positions) and
// evaluate_rpe.py --fixed_delta --delta 1 --delta_unit s. Host-side: this allocates.

#include <cstdint>
#include <vector>

#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

struct StampedPose {
  double stamp_s;  // the benchmark works in float seconds, so do we
  SE3 T_w_c;
};

// Pairs (index into first, index into second), sorted by the first's stamp.
std::vector<std::pair<int, int>> associate(const std::vector<double>& first,
                                           const std::vector<double>& second, double offset_s = 0.0,
                                           double max_difference_s = 0.02);

struct AteResult {
  int compared = 0;
  double rmse_m = 0, mean_m = 0, median_m = 0, std_m = 0, min_m = 0, max_m = 0;
  SE3 T_gt_est;  // the alignment
};
// Returns false when fewer than 2 poses associate.
bool evaluate_ate(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est,
                  AteResult* out);

struct RpeResult {
  int compared = 0;
  double trans_rmse_m = 0, trans_mean_m = 0, trans_median_m = 0;
  double rot_rmse_deg = 0, rot_mean_deg = 0, rot_median_deg = 0;
};
// Per delta_s seconds (1.0 gives the benchmark's "per second" numbers).
bool evaluate_rpe(const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est,
                  double delta_s, RpeResult* out);

// Fraction of the sequence's frames (with ground truth within 0.02 s) that have an estimate.
struct Coverage {
  int frames = 0;     // frames of the sequence that have ground truth
  int estimated = 0;  // of those, frames with an estimated pose
  double fraction() const { return frames > 0 ? static_cast<double>(estimated) / frames : 0.0; }
};
Coverage evaluate_coverage(const std::vector<double>& frame_stamps,
                           const std::vector<StampedPose>& gt, const std::vector<StampedPose>& est);

// False-valid poses (ours, not the benchmark's): pose i is checked against the earliest
// estimate j within the preceding window; it is false-valid when the estimated motion from j to
// i differs from the ground truth's by more than the limits, E = (P_i^-1 P_j)^-1 (Q_i^-1 Q_j).
struct FalseValidLimits {
  double window_s = 0.5;
  double max_translation_m = 0.10;
  double max_rotation_deg = 5.0;
};
struct FalseValidResult {
  int checked = 0;  // poses with an earlier estimate in the window and ground truth at both
  int count = 0;
  double worst_translation_m = 0, worst_rotation_deg = 0;
  std::vector<double> stamps_s;  // of every false-valid pose
  double first_stamp_s() const { return stamps_s.empty() ? 0.0 : stamps_s.front(); }
};
FalseValidResult evaluate_false_valid(const std::vector<StampedPose>& gt,
                                      const std::vector<StampedPose>& est,
                                      const FalseValidLimits& limits = FalseValidLimits());

// The ground truth at t: linear in position, slerped in rotation, between the samples that
// bracket t; false when there are none or they are more than max_gap_s apart.
bool interpolate_pose(const std::vector<StampedPose>& gt, double t, double max_gap_s, SE3* out);

// The normalised estimation error squared (NEES) of frame-to-frame motion, ours: for each
// pair of consecutive estimates at most max_gap_s apart (or 1.5 times their median interval,
// for a camera slower than 15 Hz), e = log(D_gt^-1 D_est) with
// D = P_{i-1}^-1 P_i, (translation, rotation) in camera i, against the covariance
// C_{i-1} + C_i of the two poses' reported covariances (same order, camera frame). Ground truth
// is interpolated at the estimates' stamps. A consistent covariance averages 6.
//
// Misleading poses (ours): pose i is misleading when its frame-to-frame error lies outside the
// 99.99 % region of C_{i-1} + C_i plus the ground truth's own noise (NEES beyond the chi-square
// quantile), and the part of the error beyond that region (the error less its radial
// projection onto the region's boundary) exceeds 1 cm or 1 degree: a pose the covariance sent
// with it says cannot be that wrong, and it is.
struct IntegrityLimits {
  double chi2_99_99 = 27.8563;            // chi-square, 6 degrees of freedom, 99.99 %
  double gt_translation_sigma_m = 0.001;  // per axis
  double gt_rotation_sigma_rad = 0.1 * 3.14159265358979 / 180.0;
  double max_excess_m = 0.01;
  double max_excess_rad = 1.0 * 3.14159265358979 / 180.0;
};
struct NeesResult {
  int pairs = 0;
  double mean = 0, median = 0, p99 = 0;
  double mean_translation = 0, mean_rotation = 0;  // the 3-dof parts, each consistent at 3
  int misleading = 0;
  double worst_excess_m = 0, worst_excess_deg = 0;
  std::vector<double> misleading_stamps_s;
};
NeesResult evaluate_frame_to_frame_nees(const std::vector<StampedPose>& gt,
                                        const std::vector<StampedPose>& est,
                                        const std::vector<Eigen::Matrix<double, 6, 6>>& covariance,
                                        double max_gap_s = 0.1,
                                        const IntegrityLimits& limits = IntegrityLimits());

}  // namespace rgbdtam

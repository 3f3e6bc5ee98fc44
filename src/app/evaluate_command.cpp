#include "evaluate_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "json_line.hpp"
#include "output_guard.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "trajectory_plot.hpp"

namespace rgbdtam {

EvaluationReport evaluate_all(const std::vector<StampedPose>& gt,
                              const std::vector<StampedPose>& est,
                              const std::vector<double>* frame_stamps) {
  EvaluationReport r;
  r.ate_ok = evaluate_ate(gt, est, &r.ate);
  r.rpe_ok = evaluate_rpe(gt, est, 1.0, &r.rpe);
  r.false_valid = evaluate_false_valid(gt, est);
  if (frame_stamps != nullptr) {
    r.coverage = evaluate_coverage(*frame_stamps, gt, est);
    r.has_coverage = true;
  }
  return r;
}

void print_report(const EvaluationReport& r, bool json, const char* label) {
  if (json) {
    JsonLine j;
    j.integer("poses_compared", r.ate.compared)
        .number("ate_rmse_cm", r.ate.rmse_m * 100)
        .number("ate_mean_cm", r.ate.mean_m * 100)
        .number("ate_median_cm", r.ate.median_m * 100)
        .number("ate_max_cm", r.ate.max_m * 100)
        .integer("rpe_pairs", r.rpe.compared)
        .number("rpe_trans_rmse_cm_per_s", r.rpe.trans_rmse_m * 100)
        .number("rpe_rot_rmse_deg_per_s", r.rpe.rot_rmse_deg);
    if (r.has_coverage) {
      j.number("coverage", r.coverage.fraction())
          .integer("frames_with_gt", r.coverage.frames)
          .integer("frames_estimated", r.coverage.estimated);
    }
    const FalseValidResult& f = r.false_valid;
    j.integer("false_valid", f.count)
        .integer("false_valid_checked", f.checked)
        .number("false_valid_worst_trans_cm", f.worst_translation_m * 100)
        .number("false_valid_worst_rot_deg", f.worst_rotation_deg);
    if (f.count > 0) j.number("false_valid_first_stamp_s", f.first_stamp_s(), 6);
    if (r.nees.pairs > 0) {
      j.integer("nees_pairs", r.nees.pairs)
          .number("nees_mean", r.nees.mean)
          .number("nees_median", r.nees.median)
          .number("nees_p99", r.nees.p99)
          .integer("misleading", r.nees.misleading)
          .number("misleading_worst_excess_cm", r.nees.worst_excess_m * 100)
          .number("misleading_worst_excess_deg", r.nees.worst_excess_deg);
    }
    j.end();
    return;
  }
  if (!r.ate_ok) {
    std::printf("ATE: fewer than 2 poses associate with the ground truth\n");
    return;
  }
  std::printf("ATE (%s): RMSE %.2f cm, mean %.2f, median %.2f, max %.2f cm over %d poses\n", label,
              r.ate.rmse_m * 100, r.ate.mean_m * 100, r.ate.median_m * 100, r.ate.max_m * 100,
              r.ate.compared);
  if (r.rpe_ok) {
    std::printf(
        "RPE (delta 1 s): translation RMSE %.2f cm/s, rotation RMSE %.3f deg/s over %d "
        "pairs\n",
        r.rpe.trans_rmse_m * 100, r.rpe.rot_rmse_deg, r.rpe.compared);
  }
  if (r.has_coverage) {
    std::printf("coverage: %.1f %% (%d of %d frames with ground truth)\n",
                100.0 * r.coverage.fraction(), r.coverage.estimated, r.coverage.frames);
  }
  const FalseValidResult& f = r.false_valid;
  const FalseValidLimits limits;
  std::printf(
      "false-valid (motion over %.1f s off by > %.0f cm or > %.0f deg): %d of %d poses checked; "
      "worst %.2f cm, %.2f deg",
      limits.window_s, limits.max_translation_m * 100, limits.max_rotation_deg, f.count, f.checked,
      f.worst_translation_m * 100, f.worst_rotation_deg);
  if (f.count > 0) std::printf("; first at %.6f s", f.first_stamp_s());
  std::printf("\n");
  if (r.nees.pairs > 0) {
    std::printf(
        "covariance (frame-to-frame NEES, consistent at 6): mean %.2f, median %.2f, 99th "
        "percentile %.2f over %d pairs; translation %.2f, rotation %.2f (each consistent at 3)\n",
        r.nees.mean, r.nees.median, r.nees.p99, r.nees.pairs, r.nees.mean_translation,
        r.nees.mean_rotation);
    std::printf(
        "misleading (frame-to-frame error beyond the covariance's 99.99 %% region by > 1 cm or "
        "> 1 deg): %d of %d; worst beyond it %.2f cm, %.2f deg\n",
        r.nees.misleading, r.nees.pairs, r.nees.worst_excess_m * 100, r.nees.worst_excess_deg);
  }
}

// Each estimate's covariance from a `replay --covariance` file, matched by stamp (NaN for an
// estimate the file does not cover, which the NEES then leaves out).
Status covariances_of(const char* path, const std::vector<StampedPose>& est,
                      std::vector<Eigen::Matrix<double, 6, 6>>* out) {
  std::vector<StampedCovariance> read;
  int bad = 0;
  RGBDTAM_RETURN_IF_ERROR(read_tum_covariances(path, &read, &bad));
  if (bad > 0) std::fprintf(stderr, "rgbdtam eval: skipped %d unreadable lines in %s\n", bad, path);
  // The files print stamps to the microsecond.
  constexpr double kSameStampS = 1e-6;
  out->assign(est.size(), Eigen::Matrix<double, 6, 6>::Constant(NAN));
  int matched = 0;
  for (size_t i = 0; i < est.size(); ++i) {
    const auto at =
        std::lower_bound(read.begin(), read.end(), est[i].stamp_s - kSameStampS,
                         [](const StampedCovariance& c, double t) { return c.stamp_s < t; });
    if (at != read.end() && std::fabs(at->stamp_s - est[i].stamp_s) <= kSameStampS) {
      (*out)[i] = at->covariance;
      ++matched;
    }
  }
  if (matched == 0) {
    return Status::error(StatusCode::kInvalidArgument, "%s: no covariance at an estimate's stamp",
                         path);
  }
  return Status::ok();
}

int evaluate_command(int argc, char** argv) {
  const char* gt_path = nullptr;
  const char* est_path = nullptr;
  const char* frames_path = nullptr;
  const char* plot_path = nullptr;
  const char* covariance_path = nullptr;
  bool json = false;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) {
      json = true;
    } else if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      frames_path = argv[++i];
    } else if (std::strcmp(argv[i], "--plot") == 0 && i + 1 < argc) {
      plot_path = argv[++i];
    } else if (std::strcmp(argv[i], "--covariance") == 0 && i + 1 < argc) {
      covariance_path = argv[++i];
    } else if (argv[i][0] == '-') {
      std::fprintf(stderr, "rgbdtam eval: unknown option '%s'\n", argv[i]);
      return 2;
    } else if (gt_path == nullptr) {
      gt_path = argv[i];
    } else if (est_path == nullptr) {
      est_path = argv[i];
    } else {
      std::fprintf(stderr, "rgbdtam eval: unexpected argument '%s'\n", argv[i]);
      return 2;
    }
  }
  if (gt_path == nullptr || est_path == nullptr) {
    std::fprintf(stderr,
                 "usage: rgbdtam eval <groundtruth.txt> <estimate.txt> [--json] "
                 "[--frames rgb.txt] [--plot out.svg] [--covariance estimate.cov]\n");
    return 2;
  }
  if (!outputs_are_safe("rgbdtam eval", {{"--plot", given_path(plot_path)}},
                        {{"the ground truth", gt_path},
                         {"the estimate", est_path},
                         {"--frames", given_path(frames_path)},
                         {"--covariance", given_path(covariance_path)}},
                        {})) {
    return 2;
  }
  std::vector<StampedPose> gt, est;
  int bad_gt = 0, bad_est = 0;
  for (auto [path, traj, bad] :
       {std::make_tuple(gt_path, &gt, &bad_gt), std::make_tuple(est_path, &est, &bad_est)}) {
    const Status s = read_tum_trajectory(path, traj, bad);
    if (!s.is_ok()) {
      std::fprintf(stderr, "rgbdtam eval: %s\n", s.message());
      return 1;
    }
  }
  for (auto [path, bad] : {std::make_pair(gt_path, bad_gt), std::make_pair(est_path, bad_est)}) {
    if (bad > 0)
      std::fprintf(stderr, "rgbdtam eval: skipped %d unreadable lines in %s\n", bad, path);
  }
  // Coverage counts against the sequence's frame list: rgb.txt beside the ground truth.
  std::string frames = frames_path != nullptr ? frames_path : "";
  if (frames.empty()) {
    const std::string gt_str = gt_path;
    const size_t slash = gt_str.find_last_of('/');
    frames = (slash == std::string::npos ? std::string(".") : gt_str.substr(0, slash)) + "/rgb.txt";
  }
  std::vector<double> stamps;
  const Status frames_read = read_tum_stamps(frames.c_str(), &stamps);
  const bool have_frames = frames_read.is_ok();
  if (!have_frames && frames_path != nullptr) {
    std::fprintf(stderr, "rgbdtam eval: --frames: %s\n", frames_read.message());
    return 1;
  }
  if (!have_frames) {
    std::fprintf(stderr,
                 "rgbdtam eval: no coverage: no frame list beside the ground truth (%s); give "
                 "--frames rgb.txt\n",
                 frames.c_str());
  }
  EvaluationReport r = evaluate_all(gt, est, have_frames ? &stamps : nullptr);
  if (covariance_path != nullptr) {
    std::vector<Eigen::Matrix<double, 6, 6>> covariances;
    const Status read = covariances_of(covariance_path, est, &covariances);
    if (!read.is_ok()) {
      std::fprintf(stderr, "rgbdtam eval: --covariance: %s\n", read.message());
      return 1;
    }
    r.nees = evaluate_frame_to_frame_nees(gt, est, covariances);
  }
  print_report(r, json, "all poses in the file");
  if (plot_path != nullptr && r.ate_ok) {
    PlotInput plot;
    plot.gt = &gt;
    plot.est = &est;
    plot.frame_stamps = have_frames ? &stamps : nullptr;
    plot.report = &r;
    plot.title = std::string(est_path) + " against " + gt_path;
    const Status written = write_trajectory_svg(plot_path, plot);
    if (!written.is_ok()) {
      std::fprintf(stderr, "rgbdtam eval: --plot: %s\n", written.message());
      return 1;
    }
    if (!json) std::printf("plot: %s\n", plot_path);
  }
  return r.ate_ok ? 0 : 1;
}

}  // namespace rgbdtam

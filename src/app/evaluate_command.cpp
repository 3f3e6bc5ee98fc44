#include "evaluate_command.hpp"

#include <cstdio>
#include <cstring>
#include <string>

#include "rgbdtam/hal/tum_trajectory.hpp"

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
    std::printf(
        "{\"poses_compared\": %d, \"ate_rmse_cm\": %.4f, \"ate_mean_cm\": %.4f, "
        "\"ate_median_cm\": %.4f, \"ate_max_cm\": %.4f, \"rpe_pairs\": %d, "
        "\"rpe_trans_rmse_cm_per_s\": %.4f, \"rpe_rot_rmse_deg_per_s\": %.4f",
        r.ate.compared, r.ate.rmse_m * 100, r.ate.mean_m * 100, r.ate.median_m * 100,
        r.ate.max_m * 100, r.rpe.compared, r.rpe.trans_rmse_m * 100, r.rpe.rot_rmse_deg);
    if (r.has_coverage) {
      std::printf(", \"coverage\": %.4f, \"frames_with_gt\": %d, \"frames_estimated\": %d",
                  r.coverage.fraction(), r.coverage.frames, r.coverage.estimated);
    }
    const FalseValidResult& f = r.false_valid;
    std::printf(
        ", \"false_valid\": %d, \"false_valid_checked\": %d, "
        "\"false_valid_worst_trans_cm\": %.4f, \"false_valid_worst_rot_deg\": %.4f",
        f.count, f.checked, f.worst_translation_m * 100, f.worst_rotation_deg);
    if (f.count > 0) std::printf(", \"false_valid_first_stamp_s\": %.6f", f.first_stamp_s);
    std::printf("}\n");
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
  if (f.count > 0) std::printf("; first at %.6f s", f.first_stamp_s);
  std::printf("\n");
}

int evaluate_command(int argc, char** argv) {
  const char* gt_path = nullptr;
  const char* est_path = nullptr;
  const char* frames_path = nullptr;
  bool json = false;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) {
      json = true;
    } else if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      frames_path = argv[++i];
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
                 "[--frames rgb.txt]\n");
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
  if (bad_est > 0)
    std::fprintf(stderr, "rgbdtam eval: skipped %d unreadable lines in %s\n", bad_est, est_path);
  // Coverage counts against the sequence's frame list: rgb.txt beside the ground truth.
  std::string frames = frames_path != nullptr ? frames_path : "";
  if (frames.empty()) {
    const std::string gt_str = gt_path;
    const size_t slash = gt_str.find_last_of('/');
    frames = (slash == std::string::npos ? std::string(".") : gt_str.substr(0, slash)) + "/rgb.txt";
  }
  std::vector<double> stamps;
  const bool have_frames = read_tum_stamps(frames.c_str(), &stamps).is_ok();
  const EvaluationReport r = evaluate_all(gt, est, have_frames ? &stamps : nullptr);
  print_report(r, json, "all poses in the file");
  return r.ate_ok ? 0 : 1;
}

}  // namespace rgbdtam

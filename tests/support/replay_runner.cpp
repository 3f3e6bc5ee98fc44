#include "replay_runner.hpp"

#include <gtest/gtest.h>

#include "config_files.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"

namespace rgbdtam::testing {

ReplayOutcome replay_and_evaluate(const std::string& sequence, const std::string& config,
                                  std::initializer_list<const char*> overrides, MapSink* map_sink,
                                  MapFiles map_files) {
  ReplayOutcome out;
  ReplayOptions opt;
  opt.map_sink = map_sink;
  opt.map_in_path = map_files.in;
  opt.map_out_path = map_files.out;
  opt.sequence = sequence.c_str();
  opt.progress = false;
  if (!read_params_file(config.c_str(), &opt.params).is_ok()) return out;
  for (const char* o : overrides) {
    if (!set_param(o, "test", &opt.params).is_ok()) return out;
  }
  ReplayJob job;
  out.status = job.init(opt);
  if (!out.status.is_ok()) return out;
  while (job.step()) {
  }
  out.status = job.finish();
  if (!out.status.is_ok()) return out;
  std::vector<StampedPose> gt;
  int bad = 0;
  if (!read_tum_trajectory((sequence + "/groundtruth.txt").c_str(), &gt, &bad).is_ok()) return out;
  std::vector<double> stamps;
  for (int i = 0; i < job.source().rgb_list().size; ++i) {
    stamps.push_back(job.source().rgb_list().entries[i].timestamp_ns * 1e-9);
  }
  out.report = evaluate_all(gt, job.estimates(), &stamps);
  out.report.nees = evaluate_frame_to_frame_nees(gt, job.estimates(), job.covariances());
  out.final_report = evaluate_all(gt, job.final_estimates(), &stamps);
  if (job.loop_enabled()) out.loop = job.loop().counters();
  out.counters = job.counters();
  out.estimates = job.estimates();
  out.found_in_map_at_frame = job.found_in_map_at_frame();
  out.tracking_median_ms = job.tracking_time().percentile_ms(0.5);
  out.ran = true;
  return out;
}

void expect_tracked_or_lost(const ReplayOutcome& out, const std::string& label,
                            double min_coverage) {
  ASSERT_TRUE(out.ran) << label;
  EXPECT_EQ(out.report.false_valid.count, 0) << label;
  EXPECT_GT(out.report.false_valid.checked, 0) << label << ": nothing was checked";
  EXPECT_GE(out.report.coverage.fraction(), min_coverage) << label;
  std::printf("%s: ATE %.2f cm, coverage %.1f %%, %d of %d false-valid, %u lost, %u retried\n",
              label.c_str(), out.report.ate.rmse_m * 100, 100 * out.report.coverage.fraction(),
              out.report.false_valid.count, out.report.false_valid.checked, out.counters.lost,
              out.counters.retried);
}

}  // namespace rgbdtam::testing

#include "replay_runner.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "config_files.hpp"
#include "config_text.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "stress_variants.hpp"
#include "test_paths.hpp"

namespace rgbdtam::testing {
namespace {
AllocationCounter g_counter;
}  // namespace

void count_allocations_in_replays(AllocationCounter counter) { g_counter = counter; }

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
  if (g_counter.arm != nullptr) g_counter.arm();
  while (job.step()) {
  }
  out.status = job.finish();
  if (g_counter.disarm != nullptr) out.allocations_after_init = g_counter.disarm();
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

std::string clip_in_a_depth_camera_of_its_own(const std::string& dir) {
  const std::string config = source_path("config/tum_fr1.conf");
  DepthCameraShape d435;
  d435.focal_scale = 0.85;
  d435.width_px = 848;
  d435.height_px = 480;
  if (!unregister_depth(source_path("data/tum_fr1_xyz_clip"), dir + "/d435", config, d435)) {
    return "";
  }
  // The vocabulary named where it lies, since the config moves out of the source tree.
  std::ifstream base(config), keys(dir + "/d435/depth_camera.conf");
  std::stringstream base_text, key_text;
  base_text << base.rdbuf();
  key_text << keys.rdbuf();
  const std::string combined = dir + "/d435.conf";
  std::ofstream(combined) << with_changes(
      base_text.str(),
      key_text.str() + "loop.vocabulary = " + source_path("data/vocabulary/tum-k10-l4.voc") + "\n");
  return combined;
}

}  // namespace rgbdtam::testing

// The full fr1_xyz sequence (798 frames), where the machine has it: the accuracy the
// tracking issue asks for. Skipped elsewhere, since the repository holds only a clip.
#include <gtest/gtest.h>

#include "replay_runner.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

TEST(FullSequence, Fr1XyzAllFramesAteWithinOnePointFiveCentimetres) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const auto out = testing::replay_and_evaluate(seq, testing::source_path("config/tum_fr1.conf"));
  ASSERT_TRUE(out.ran);
  EXPECT_EQ(out.counters.lost, 0u);
  EXPECT_DOUBLE_EQ(out.report.coverage.fraction(), 1.0);
  ASSERT_TRUE(out.report.ate_ok);
  EXPECT_LE(out.report.ate.rmse_m, 0.015);
  std::printf("fr1_xyz: ATE %.2f cm over %d poses, RPE %.2f cm/s %.3f deg/s\n",
              out.report.ate.rmse_m * 100, out.report.ate.compared,
              out.report.rpe.trans_rmse_m * 100, out.report.rpe.rot_rmse_deg);
}

// The mapping issue: the fused multi-view map must not cost accuracy (measured 0.84 cm with it,
// 0.88 cm tracking on sensor depth alone).
TEST(FullSequence, Fr1XyzMappingIsNoWorseThanTrackingAloneAndWithinOnePointTwoCentimetres) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const std::string config = testing::source_path("config/tum_fr1.conf");
  const auto mapped = testing::replay_and_evaluate(seq, config, "map.enabled=true");
  const auto alone = testing::replay_and_evaluate(seq, config, "map.enabled=false");
  ASSERT_TRUE(mapped.ran && alone.ran);
  ASSERT_TRUE(mapped.report.ate_ok && alone.report.ate_ok);
  EXPECT_EQ(mapped.counters.lost, 0u);
  EXPECT_LE(mapped.report.ate.rmse_m, 0.012);
  EXPECT_LE(mapped.report.ate.rmse_m, alone.report.ate.rmse_m);
  std::printf("fr1_xyz all-frames ATE: %.2f cm with mapping, %.2f cm without\n",
              mapped.report.ate.rmse_m * 100, alone.report.ate.rmse_m * 100);
}

}  // namespace
}  // namespace rgbdtam

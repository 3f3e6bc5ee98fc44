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

}  // namespace
}  // namespace rgbdtam

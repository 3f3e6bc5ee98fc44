// The committed fr1_xyz clip (50 real Kinect frames) with the shipped Freiburg 1 config.
#include <gtest/gtest.h>

#include "replay_runner.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

TEST(RealClip, TracksEveryFrameWithinOnePointTwoCentimetres) {
  const auto out = testing::replay_and_evaluate(testing::source_path("data/tum_fr1_xyz_clip"),
                                                testing::source_path("config/tum_fr1.conf"));
  ASSERT_TRUE(out.ran);
  EXPECT_EQ(out.counters.frames, 50u);
  EXPECT_EQ(out.counters.tracked, 50u);
  EXPECT_EQ(out.counters.lost, 0u);
  EXPECT_DOUBLE_EQ(out.report.coverage.fraction(), 1.0);
  ASSERT_TRUE(out.report.ate_ok);
  // Measured 0.62 cm (all frames) on x86-64; the clip moves about 40 cm in 1.7 s.
  EXPECT_LT(out.report.ate.rmse_m, 0.012);
  std::printf("clip ATE %.2f cm, %d poses\n", out.report.ate.rmse_m * 100, out.report.ate.compared);
}

}  // namespace
}  // namespace rgbdtam

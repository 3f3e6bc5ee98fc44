// The committed real clip blurred along its true motion over a 33 ms exposure: tracked or
// reported lost, never a wrong pose reported as tracked. Long: rendering the blur takes seconds.
#include <gtest/gtest.h>

#include "replay_runner.hpp"
#include "stress_variants.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

TEST(RobustTracking, TheRealClipBlurredAlongItsMotionIsNeverFalseValid) {
  const std::string dir = testing::make_temp_dir("clip_blur");
  const std::string config = testing::source_path("config/tum_fr1.conf");
  ASSERT_TRUE(testing::blur_sequence(testing::source_path("data/tum_fr1_xyz_clip"), dir + "/blur",
                                     config, 33.0));
  const auto out = testing::replay_and_evaluate(dir + "/blur", config);
  testing::expect_tracked_or_lost(out, "clip blurred over 33 ms", 0.9);
  ASSERT_TRUE(out.report.ate_ok);
  EXPECT_LT(out.report.ate.rmse_m, 0.02);
}

}  // namespace
}  // namespace rgbdtam

// The committed clip's stress variants (rgbdtam-stress): played faster, with a kidnapped frame,
// with noise for its images, and wandered over. Whatever cannot be tracked is reported lost.
#include <gtest/gtest.h>

#include "replay_runner.hpp"
#include "stress_variants.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

TEST(ClipVariants, TheRealClipThreeTimesFasterIsNeverFalseValid) {
  const std::string dir = testing::make_temp_dir("clip_x3");
  ASSERT_TRUE(
      testing::decimate_sequence(testing::source_path("data/tum_fr1_xyz_clip"), dir + "/x3", 3));
  const auto out =
      testing::replay_and_evaluate(dir + "/x3", testing::source_path("config/tum_fr1.conf"));
  EXPECT_EQ(out.counters.frames, 17u);
  testing::expect_tracked_or_lost(out, "clip x3", 0.9);
}

TEST(ClipVariants, TheRealClipWithAKidnappedFrameIsNeverFalseValid) {
  // Frame 25 shows what frame 0 showed, about 20 cm back along the path.
  const std::string dir = testing::make_temp_dir("clip_kidnap");
  ASSERT_TRUE(testing::kidnap_frame(testing::source_path("data/tum_fr1_xyz_clip"),
                                    dir + "/kidnapped", 25, 0));
  const auto out =
      testing::replay_and_evaluate(dir + "/kidnapped", testing::source_path("config/tum_fr1.conf"));
  EXPECT_GE(out.counters.lost, 1u) << "the kidnapped frame";
  testing::expect_tracked_or_lost(out, "clip with a kidnapped frame", 0.9);
}

TEST(ClipVariants, DepthFromACameraOfItsOwnSizeIsRegisteredAndTrackedAsTheRegisteredClip) {
  // As a D435 over V4L2 delivers it: depth 848x480 over an 87-degree field, 2.5 cm aside.
  const std::string dir = testing::make_temp_dir("clip_depth_camera");
  const std::string clip = testing::source_path("data/tum_fr1_xyz_clip");
  const std::string config = testing::source_path("config/tum_fr1.conf");
  const std::string combined = testing::clip_in_a_depth_camera_of_its_own(dir);
  ASSERT_FALSE(combined.empty());
  const auto registered = testing::replay_and_evaluate(clip, config);
  const auto moved = testing::replay_and_evaluate(dir + "/d435", combined);
  ASSERT_TRUE(moved.ran) << moved.status.message();
  testing::expect_tracked_or_lost(moved, "clip, depth 848x480 registered in software", 1.0);
  std::printf("ATE %.2f cm registered by the sensor, %.2f cm from 848x480 in software\n",
              registered.report.ate.rmse_m * 100, moved.report.ate.rmse_m * 100);
  EXPECT_LT(moved.report.ate.rmse_m, registered.report.ate.rmse_m + 0.001) << "within 0.1 cm";
}

TEST(ClipVariants, NoiseInGivesNoPoseOut) {
  // Pure noise from the sensor once used to give confident poses metres apart. Noise depth is
  // not a surface, so no frame has depth and none can be tracked; noise colour over real depth
  // leaves the geometric term, which may track, but never wrongly.
  const std::string dir = testing::make_temp_dir("clip_noise");
  const std::string clip = testing::source_path("data/tum_fr1_xyz_clip");
  const std::string config = testing::source_path("config/tum_fr1.conf");
  for (const char* kind : {"depth", "both"}) {
    ASSERT_TRUE(testing::noise_sequence(clip, dir + "/" + kind, config, kind, 3));
    const auto out = testing::replay_and_evaluate(dir + "/" + kind, config);
    EXPECT_EQ(out.counters.frames, 50u) << kind;
    EXPECT_EQ(out.counters.tracked, 0u) << kind << " noise: no pose";
    EXPECT_EQ(out.counters.depth_not_surface, 50u) << kind;
  }
  ASSERT_TRUE(testing::noise_sequence(clip, dir + "/colour", config, "colour", 3));
  const auto colour = testing::replay_and_evaluate(dir + "/colour", config);
  EXPECT_EQ(colour.counters.depth_not_surface, 0u);
  testing::expect_tracked_or_lost(colour, "clip with noise for colour", 0.9);
}

// Issue 35, items 2 and 18: depth as a failed sensor gives it. One value in every pixel, frame
// after frame, repeats the last depth frame while the image moves: from its second repeat on
// every frame is lost (the first frame is the origin, the second within a frame's motion of
// it). Depth with no pixel in range is no depth: nothing is tracked, and the frames are
// counted as without depth.
TEST(ClipVariants, DepthAsAFailedSensorGivesItSendsNoPose) {
  const std::string dir = testing::make_temp_dir("clip_stuck_depth");
  const std::string clip = testing::source_path("data/tum_fr1_xyz_clip");
  const std::string config = testing::source_path("config/tum_fr1.conf");
  ASSERT_TRUE(testing::noise_sequence(clip, dir + "/frozen", config, "depth-1m", 1));
  const auto frozen = testing::replay_and_evaluate(dir + "/frozen", config);
  EXPECT_EQ(frozen.counters.frames, 50u);
  EXPECT_LE(frozen.counters.tracked, 2u);
  EXPECT_EQ(frozen.counters.depth_frozen, 48u);
  EXPECT_EQ(frozen.report.false_valid.count, 0);
  for (const char* kind : {"depth-zero", "depth-saturated"}) {
    ASSERT_TRUE(testing::noise_sequence(clip, dir + "/" + kind, config, kind, 1));
    const auto out = testing::replay_and_evaluate(dir + "/" + kind, config);
    EXPECT_EQ(out.counters.tracked, 0u) << kind;
    EXPECT_EQ(out.counters.without_depth, 50u) << kind;
  }
}

// The clip wandered over (rgbdtam-stress wander, as the long soak's sequence is made): reversals,
// twice the speed and jumps after outages, with every frame's ground truth carried along.
TEST(ClipVariants, TheClipWanderedOverIsNeverFalseValid) {
  const std::string dir = testing::make_temp_dir("clip_wander");
  const std::string config = testing::source_path("config/tum_fr1.conf");
  ASSERT_TRUE(testing::wander_sequence(testing::source_path("data/tum_fr1_xyz_clip"),
                                       dir + "/wander", config, 120, 1));
  const auto out = testing::replay_and_evaluate(dir + "/wander", config);
  EXPECT_EQ(out.counters.frames, 120u);
  // A relocalisation within 0.5 s of the last valid pose (a short outage) is tracked, but its
  // poses are withheld until 0.5 s after that pose: 95 % of the other frames have a pose.
  EXPECT_LE(out.counters.withheld, 15u) << "no more than one window's frames";
  const double withheld = static_cast<double>(out.counters.withheld) / out.counters.frames;
  testing::expect_tracked_or_lost(out, "the clip wandered over", 0.95 - withheld);
}

}  // namespace
}  // namespace rgbdtam

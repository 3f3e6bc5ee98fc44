// The committed clip's stress variants (rgbdtam-stress): played faster, with a kidnapped frame,
// with noise for its images, and wandered over. Whatever cannot be tracked is reported lost.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "replay_runner.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "stress_variants.hpp"
#include "synthetic_scene.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

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

// The data lines of a TUM list (rgb.txt, depth.txt).
int list_entries(const std::string& path) {
  std::ifstream in(path);
  int n = 0;
  for (std::string line; std::getline(in, line);) n += !line.empty() && line[0] != '#';
  return n;
}

TEST(ClipVariants, ADepthCopyKeepsEveryDepthImageWhateverThePairing) {
  // Played at half the frame rate, half the depth images pair with no colour frame under the
  // config's offset; a copy replayed under another offset still needs them.
  const std::string dir = testing::make_temp_dir("clip_depth_copy");
  const std::string clip = testing::source_path("data/tum_fr1_xyz_clip");
  ASSERT_TRUE(testing::decimate_sequence(clip, dir + "/x2", 2));
  ASSERT_TRUE(testing::dither_depth(dir + "/x2", dir + "/dithered",
                                    testing::source_path("config/tum_fr1.conf"), 1));
  const int listed = list_entries(dir + "/x2/depth.txt");
  EXPECT_GT(listed, list_entries(dir + "/x2/rgb.txt") + 10);
  EXPECT_EQ(list_entries(dir + "/dithered/depth.txt"), listed);
}

// The disparity each noisy depth pixel is off by, f b (1/z_noisy - 1/z), px, over the first
// `frames` depth images of two copies of one sequence (0 where either has no depth), and
// whether every hole of the first stayed a hole.
struct DisparityErrors {
  std::vector<double> px;
  int width = 0;
  bool holes_kept = true;
};
DisparityErrors disparity_errors(const std::string& clean, const std::string& noisy,
                                 const Params& p, int frames) {
  DisparityErrors e;
  const SensorImageSize size = sensor_image_size(p);
  e.width = size.depth_width_px;
  TumReplaySource a, b;
  EXPECT_TRUE(
      a.open(clean.c_str(), size, p.sensor.max_rgb_depth_dt_ns, p.sensor.depth_time_offset_ns)
          .is_ok());
  EXPECT_TRUE(
      b.open(noisy.c_str(), size, p.sensor.max_rgb_depth_dt_ns, p.sensor.depth_time_offset_ns)
          .is_ok());
  ImageU8 gray_a, gray_b;
  ImageU16 depth_a, depth_b;
  gray_a.allocate(size.width_px, size.height_px);
  gray_b.allocate(size.width_px, size.height_px);
  depth_a.allocate(size.depth_width_px, size.depth_height_px);
  depth_b.allocate(size.depth_width_px, size.depth_height_px);
  const double fb_raw = p.sensor.depth_focal_px * p.sensor.baseline_m * p.sensor.depth_factor;
  for (int f = 0; f < frames; ++f) {
    SensorFrame fa, fb;
    Status warning;
    if (!a.next_into(&gray_a, &depth_a, &fa, &warning).is_ok() ||
        !b.next_into(&gray_b, &depth_b, &fb, &warning).is_ok() || fa.depth == nullptr ||
        fb.depth == nullptr) {
      ADD_FAILURE() << "frame " << f << " of both copies, with depth";
      break;
    }
    for (size_t i = 0; i < size.depth_pixels(); ++i) {
      const int za = fa.depth[i], zb = fb.depth[i];
      if (za == 0 && zb != 0) e.holes_kept = false;
      e.px.push_back(za == 0 || zb == 0 ? 0.0 : fb_raw / zb - fb_raw / za);
    }
  }
  return e;
}

// Mean, spread and the correlation of horizontal neighbours (x, x + 1) where pair(x) says.
template <typename Pair>
void moments(const DisparityErrors& e, Pair pair, double* mean, double* sigma, double* corr) {
  double n = 0, s = 0, ss = 0, nn = 0, sxy = 0;
  for (size_t i = 0; i + 1 < e.px.size(); ++i) {
    const double v = e.px[i];
    if (v == 0.0) continue;
    n += 1, s += v, ss += v * v;
    const int x = static_cast<int>(i % e.width);
    if (x + 1 < e.width && pair(x) && e.px[i + 1] != 0.0) nn += 1, sxy += v * e.px[i + 1];
  }
  *mean = s / n;
  *sigma = std::sqrt(ss / n - *mean * *mean);
  *corr = (sxy / nn - *mean * *mean) / (*sigma * *sigma);
  std::printf("disparity error mean %.4f px, sigma %.4f px, neighbours' correlation %.3f\n", *mean,
              *sigma, *corr);
}

TEST(ClipVariants, SensorNoiseHasTheModelsSpreadAndSharesItWithinABlock) {
  const std::string dir = testing::make_temp_dir("clip_sensor_noise");
  const std::string clip = testing::source_path("data/tum_fr1_xyz_clip");
  const std::string config = testing::source_path("config/tum_fr1.conf");
  char* text = nullptr;
  ASSERT_TRUE(read_text_file(config.c_str(), 1 << 20, &text).is_ok());
  Params p;
  const Status parsed = parse_params(text, config.c_str(), &p);
  delete[] text;
  ASSERT_TRUE(parsed.is_ok()) << parsed.message();
  // Gaussian disparity noise, then the disparity's step (uniform: q^2 / 12 more variance).
  const double q = p.sensor.disparity_quantum_px;
  const double expected =
      std::sqrt(p.sensor.disparity_sigma_px * p.sensor.disparity_sigma_px + q * q / 12.0);
  constexpr int kBlockPx = 8;
  ASSERT_TRUE(testing::sensor_noise_depth(clip, dir + "/white", config, 1, 1));
  ASSERT_TRUE(testing::sensor_noise_depth(clip, dir + "/blocks", config, 1, kBlockPx));
  const DisparityErrors white = disparity_errors(clip, dir + "/white", p, 3);
  const DisparityErrors blocks = disparity_errors(clip, dir + "/blocks", p, 3);
  EXPECT_TRUE(white.holes_kept);
  EXPECT_TRUE(blocks.holes_kept);
  const auto any = [](int) { return true; };
  const auto inside = [](int x) { return x % kBlockPx != kBlockPx - 1; };
  const auto across = [](int x) { return x % kBlockPx == kBlockPx - 1; };
  double mean, sigma, corr;
  moments(white, any, &mean, &sigma, &corr);
  EXPECT_NEAR(mean, 0.0, 0.01) << "px";
  EXPECT_NEAR(sigma, expected, 0.05 * expected) << "px";
  EXPECT_LT(std::fabs(corr), 0.05) << "white noise: neighbours independent";
  moments(blocks, inside, &mean, &sigma, &corr);
  EXPECT_NEAR(sigma, expected, 0.1 * expected) << "px";
  EXPECT_GT(corr, 0.9) << "neighbours within a block share their draw";
  moments(blocks, across, &mean, &sigma, &corr);
  EXPECT_LT(std::fabs(corr), 0.1) << "neighbours across a block's edge do not";
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

// A pan whose depth is taken later than its colour (a Kinect's unsynchronised streams): each
// depth image is the room seen from where the camera was then, and is stamped so.
TEST(ClipVariants, APansLateDepthIsTakenAndStampedLate) {
  const std::string dir = testing::make_temp_dir("pan_late_depth");
  constexpr double kLateMs = 8.0, kPeakDegS = 60.0, kFps = 30.0;
  constexpr int kFrames = 3;
  ASSERT_TRUE(testing::pan_sequence(dir + "/pan", kPeakDegS, kFrames, kFps, kLateMs));
  EXPECT_FALSE(testing::pan_sequence(dir + "/beyond", kPeakDegS, kFrames, kFps, 20.0))
      << "beyond what pairing takes";
  const testing::SyntheticScene scene = testing::pan_scene(kPeakDegS);
  const Params p = testing::synthetic_params(scene);
  const SensorImageSize size = sensor_image_size(p);
  TumReplaySource source;
  ASSERT_TRUE(source
                  .open((dir + "/pan").c_str(), size, p.sensor.max_rgb_depth_dt_ns,
                        p.sensor.depth_time_offset_ns)
                  .is_ok());
  ImageU8 gray;
  ImageU16 depth;
  gray.allocate(size.width_px, size.height_px);
  depth.allocate(size.depth_width_px, size.depth_height_px);
  for (int i = 0; i < kFrames; ++i) {
    SensorFrame f;
    Status warning;
    ASSERT_TRUE(source.next_into(&gray, &depth, &f, &warning).is_ok());
    ASSERT_NE(f.depth, nullptr);
    const int64_t late_ns = f.depth_timestamp_ns - f.timestamp_ns - p.sensor.depth_time_offset_ns;
    EXPECT_NEAR(static_cast<double>(late_ns), kLateMs * 1e6, 1e3) << "frame " << i;
    const double t_s = i / kFps;
    const testing::SyntheticFrame then = scene.render(scene.camera_at(t_s + 1e-3 * kLateMs));
    const testing::SyntheticFrame now = scene.render(scene.camera_at(t_s));
    EXPECT_TRUE(std::equal(then.depth.begin(), then.depth.end(), f.depth)) << "frame " << i;
    EXPECT_FALSE(std::equal(now.depth.begin(), now.depth.end(), f.depth)) << "frame " << i;
  }
}

}  // namespace
}  // namespace rgbdtam

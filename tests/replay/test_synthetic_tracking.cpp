// The tracker on a synthetic sequence with exact ground truth must be sub-millimetre.
#include <gtest/gtest.h>

#include <cmath>

#include "rgbdtam/runtime/tracking_pipeline.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

Params synthetic_params(const testing::SyntheticScene& scene, const char* residuals) {
  Params p = testing::synthetic_params(scene);
  EXPECT_TRUE(ResidualConfig::parse(residuals, &p.tracker.residuals));
  return p;
}

struct PathError {
  double max_translation_m = 0;
  double max_rotation_rad = 0;
  int tracked = 0;
  uint32_t keyframes = 0;
};

// 2.4 s of the path at 10 Hz: about 15 cm and 4 degrees, across several keyframes.
constexpr int kFrames = 24;
constexpr double kFps = 10.0;

// build_after_pose: builds each keyframe right after its frame's pose, as the firmware does,
// and checks that process() itself left it for later; otherwise the next process() builds it.
PathError track_synthetic(const char* residuals, int frames, double fps,
                          bool build_after_pose = false) {
  testing::SyntheticScene scene;
  KeyframePool keyframes;
  TrackingPipeline pipeline;
  EXPECT_TRUE(pipeline.init(synthetic_params(scene, residuals), &keyframes).is_ok());
  const SE3 T_w0 = testing::SyntheticScene::pose_at(0.0);
  PathError err;
  const auto& rendered = scene.render_path(frames, fps);
  for (int i = 0; i < frames; ++i) {
    const double t = i / fps;
    const SE3 T_w_c = testing::SyntheticScene::pose_at(t);
    const testing::SyntheticFrame& f = rendered[static_cast<size_t>(i)];
    const uint32_t keyframes_before = pipeline.counters().keyframes;
    const PoseEstimate pose = pipeline.process(f.as_sensor_frame(scene.camera, i, fps));
    if (build_after_pose && i > 0 && (pose.flags & kNewKeyframe) != 0) {
      EXPECT_EQ(pipeline.counters().keyframes, keyframes_before) << "built before the pose";
      pipeline.build_pending_keyframe();
      EXPECT_EQ(pipeline.counters().keyframes, keyframes_before + 1);
      pipeline.build_pending_keyframe();
      EXPECT_EQ(pipeline.counters().keyframes, keyframes_before + 1) << "built twice";
    }
    if ((pose.flags & kPoseValid) == 0) continue;
    ++err.tracked;
    const SE3 truth = T_w0.inverse() * T_w_c;  // world = first camera
    const SE3 diff = truth.inverse() * pose.T_w_c;
    err.max_translation_m = std::max(err.max_translation_m, diff.translation().norm());
    err.max_rotation_rad = std::max(err.max_rotation_rad, so3_log(diff.quaternion()).norm());
  }
  err.keyframes = pipeline.counters().keyframes;
  return err;
}

TEST(SyntheticTracking, PaperConfigurationIsSubMillimetre) {
  const PathError e = track_synthetic("PS+GIDD", kFrames, kFps);
  EXPECT_EQ(e.tracked, kFrames);
  EXPECT_GT(e.keyframes, 1u) << "the path should cross keyframe boundaries";
  EXPECT_LT(e.max_translation_m, 1e-3);
  EXPECT_LT(e.max_rotation_rad, 1e-3);
  std::printf("PS+GIDD: max error %.3f mm, %.4f deg, %u keyframes\n", e.max_translation_m * 1e3,
              e.max_rotation_rad * 180 / M_PI, e.keyframes);
}

TEST(SyntheticTracking, AKeyframeBuiltAfterItsPoseOrAtTheNextFrameGivesTheSamePath) {
  const PathError after_pose = track_synthetic("PS+GIDD", kFrames, kFps, true);
  const PathError next_frame = track_synthetic("PS+GIDD", kFrames, kFps, false);
  EXPECT_GT(after_pose.keyframes, 1u);
  EXPECT_EQ(after_pose.keyframes, next_frame.keyframes);
  EXPECT_EQ(after_pose.tracked, next_frame.tracked);
  EXPECT_EQ(after_pose.max_translation_m, next_frame.max_translation_m);
  EXPECT_EQ(after_pose.max_rotation_rad, next_frame.max_rotation_rad);
}

TEST(SyntheticTracking, PhotometricOnlyAndGeometricOnlyAreSubMillimetreToo) {
  for (const char* config : {"PS", "GIDD"}) {
    const PathError e = track_synthetic(config, kFrames, kFps);
    EXPECT_EQ(e.tracked, kFrames) << config;
    EXPECT_LT(e.max_translation_m, 1e-3) << config;
    std::printf("%s: max error %.3f mm, %.4f deg\n", config, e.max_translation_m * 1e3,
                e.max_rotation_rad * 180 / M_PI);
  }
}

}  // namespace
}  // namespace rgbdtam

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

PathError track_synthetic(const char* residuals, int frames, double fps) {
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
    const PoseEstimate pose = pipeline.process(f.as_sensor_frame(scene.camera, i, fps));
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

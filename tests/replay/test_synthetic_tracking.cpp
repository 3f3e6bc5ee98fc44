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
  uint32_t frames_awaiting_keyframe = 0;
  bool adopted_only_when_built = true;
};

// How the keyframes are built.
enum class Building {
  kAtNextFrame,    // synchronously, ordered by the next process()
  kAfterPose,      // synchronously, right after each frame's pose, as replay does
  kLateBuilder,    // on "another thread" that the test lets run only every third frame
  kBuilderThread,  // on a thread of its own
};

// 2.4 s of the path at 10 Hz: about 15 cm and 4 degrees, across several keyframes.
constexpr int kFrames = 24;
constexpr double kFps = 10.0;

// kAfterPose also checks that process() itself left the keyframe for later.
PathError track_synthetic(const char* residuals, int frames, double fps,
                          Building mode = Building::kAtNextFrame) {
  testing::SyntheticScene scene;
  KeyframePool keyframes;
  KeyframeBuildTask building;
  KeyframeOrderQueue orders;
  KeyframeBuildThread builder_thread;
  TrackingPipeline pipeline;
  EXPECT_TRUE(pipeline.init(synthetic_params(scene, residuals), &keyframes, &building).is_ok());
  const bool threaded = mode == Building::kLateBuilder || mode == Building::kBuilderThread;
  if (threaded) {
    orders.allocate(1);
    building.connect_queue(&orders);
  }
  if (mode == Building::kBuilderThread) {
    EXPECT_TRUE(
        builder_thread.start(&orders, &building, ThreadPlacement(), "test-keyframe").is_ok());
  }
  const SE3 T_w0 = testing::SyntheticScene::pose_at(0.0);
  PathError err;
  const auto& rendered = scene.render_path(frames, fps);
  for (int i = 0; i < frames; ++i) {
    const double t = i / fps;
    const SE3 T_w_c = testing::SyntheticScene::pose_at(t);
    const testing::SyntheticFrame& f = rendered[static_cast<size_t>(i)];
    const uint32_t keyframes_before = pipeline.counters().keyframes;
    const bool built_before = orders.capacity() > 0 && orders.front() == nullptr;
    const PoseEstimate pose = pipeline.process(f.as_sensor_frame(scene.camera, i, fps));
    if (mode == Building::kLateBuilder && pipeline.counters().keyframes > keyframes_before &&
        !built_before) {
      err.adopted_only_when_built = false;
    }
    if (mode == Building::kAfterPose && i > 0 && (pose.flags & kNewKeyframe) != 0) {
      EXPECT_EQ(pipeline.counters().keyframes, keyframes_before) << "built before the pose";
      pipeline.build_pending_keyframe();
      EXPECT_EQ(pipeline.counters().keyframes, keyframes_before + 1);
      pipeline.build_pending_keyframe();
      EXPECT_EQ(pipeline.counters().keyframes, keyframes_before + 1) << "built twice";
    }
    if (threaded) pipeline.build_pending_keyframe();
    if (mode == Building::kLateBuilder && i % 3 == 2) drain(&orders, &building);
    if (mode == Building::kBuilderThread) builder_thread.notify();
    if ((pose.flags & kPoseValid) == 0) continue;
    ++err.tracked;
    const SE3 truth = T_w0.inverse() * T_w_c;  // world = first camera
    const SE3 diff = truth.inverse() * pose.T_w_c;
    err.max_translation_m = std::max(err.max_translation_m, diff.translation().norm());
    err.max_rotation_rad = std::max(err.max_rotation_rad, so3_log(diff.quaternion()).norm());
  }
  err.keyframes = pipeline.counters().keyframes;
  err.frames_awaiting_keyframe = pipeline.counters().frames_awaiting_keyframe;
  if (mode == Building::kBuilderThread) builder_thread.stop();
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
  const PathError after_pose = track_synthetic("PS+GIDD", kFrames, kFps, Building::kAfterPose);
  const PathError next_frame = track_synthetic("PS+GIDD", kFrames, kFps, Building::kAtNextFrame);
  EXPECT_GT(after_pose.keyframes, 1u);
  EXPECT_EQ(after_pose.keyframes, next_frame.keyframes);
  EXPECT_EQ(after_pose.tracked, next_frame.tracked);
  EXPECT_EQ(after_pose.max_translation_m, next_frame.max_translation_m);
  EXPECT_EQ(after_pose.max_rotation_rad, next_frame.max_rotation_rad);
}

TEST(SyntheticTracking,
     AKeyframeBuiltOffTheTrackersThreadIsAdoptedWhenBuiltAndTheTrackerNeverWaits) {
  // The builder runs every third frame only: the tracker tracks on against the last keyframe
  // meanwhile, adopts each keyframe at the first frame after it is built, and stays exact.
  const PathError late = track_synthetic("PS+GIDD", kFrames, kFps, Building::kLateBuilder);
  EXPECT_EQ(late.tracked, kFrames);
  EXPECT_GT(late.keyframes, 1u);
  EXPECT_GT(late.frames_awaiting_keyframe, 0u);
  EXPECT_TRUE(late.adopted_only_when_built);
  EXPECT_LT(late.max_translation_m, 1e-3);
  EXPECT_LT(late.max_rotation_rad, 1e-3);
  // On a thread of its own, as in the firmware.
  const PathError threaded = track_synthetic("PS+GIDD", kFrames, kFps, Building::kBuilderThread);
  EXPECT_EQ(threaded.tracked, kFrames);
  EXPECT_GT(threaded.keyframes, 1u);
  EXPECT_LT(threaded.max_translation_m, 1e-3);
  EXPECT_LT(threaded.max_rotation_rad, 1e-3);
  std::printf(
      "builder every third frame: %u keyframes, %u frames tracked against the last one "
      "while the next was built, max error %.3f mm; on its thread: %u keyframes, %u, "
      "%.3f mm\n",
      late.keyframes, late.frames_awaiting_keyframe, late.max_translation_m * 1e3,
      threaded.keyframes, threaded.frames_awaiting_keyframe, threaded.max_translation_m * 1e3);
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

// Robust tracking: what cannot be tracked is reported lost, what is reported tracked is right.
// Synthetic sequences with exact ground truth (the real clip's variants: test_clip_variants).
#include <gtest/gtest.h>

#include <cmath>

#include "rgbdtam/runtime/tracking_pipeline.hpp"
#include "synthetic_scene.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

struct Verdicts {
  int valid = 0, lost = 0;
  double worst_translation_m = 0, worst_rotation_rad = 0;  // over the valid poses
};

// Tracks the frames (truth: T_w_c of each) and compares every valid pose with the truth.
Verdicts track_and_judge(const testing::SyntheticScene& scene,
                         const std::vector<testing::SyntheticFrame>& frames,
                         const std::vector<SE3>& truth, double fps,
                         std::vector<PoseEstimate>* poses = nullptr) {
  KeyframePool keyframes;
  TrackingPipeline pipeline;
  EXPECT_TRUE(pipeline.init(testing::synthetic_params(scene), &keyframes).is_ok());
  Verdicts v;
  for (size_t i = 0; i < frames.size(); ++i) {
    const PoseEstimate pose =
        pipeline.process(frames[i].as_sensor_frame(scene.camera, static_cast<int>(i), fps));
    if (poses != nullptr) poses->push_back(pose);
    if ((pose.flags & kPoseValid) == 0) {
      v.lost += (pose.flags & kLost) != 0 ? 1 : 0;
      continue;
    }
    ++v.valid;
    const SE3 diff = (truth[0].inverse() * truth[i]).inverse() * pose.T_w_c;
    v.worst_translation_m = std::max(v.worst_translation_m, diff.translation().norm());
    v.worst_rotation_rad = std::max(v.worst_rotation_rad, so3_log(diff.quaternion()).norm());
  }
  return v;
}

TEST(RobustTracking, AKidnappedFrameIsReportedLostAndTrackingResumes) {
  // 3 s at 10 Hz of the gentle path; frame 15 is seen from 80 degrees to the side, as if the
  // sensor had been swapped for a moment. No estimate can be right for it from the keyframe.
  const testing::SyntheticScene scene = testing::SyntheticScene::half_resolution();
  constexpr int kFrames = 30, kKidnapped = 15;
  constexpr double kFps = 10.0;
  std::vector<testing::SyntheticFrame> frames = scene.render_path(kFrames, kFps);
  std::vector<SE3> truth;
  for (int i = 0; i < kFrames; ++i) truth.push_back(scene.camera_at(i / kFps));
  const SE3 elsewhere =
      truth[kKidnapped] * SE3(so3_exp(Vector3d(0, 80 * M_PI / 180, 0)), Vector3d(0.3, 0, -0.2));
  frames[kKidnapped] = scene.render(elsewhere);
  truth[kKidnapped] = elsewhere;
  std::vector<PoseEstimate> poses;
  const Verdicts v = track_and_judge(scene, frames, truth, kFps, &poses);
  const PoseEstimate& kidnapped = poses[kKidnapped];
  EXPECT_EQ(kidnapped.flags & kPoseValid, 0u) << "a pose for the kidnapped frame";
  EXPECT_NE(kidnapped.flags & kLost, 0u);
  EXPECT_NE(kidnapped.failed_checks, 0u) << "a lost frame names the checks it failed";
  EXPECT_EQ(v.valid, kFrames - 1) << "every other frame is tracked";
  EXPECT_LT(v.worst_translation_m, 0.01);
  EXPECT_LT(v.worst_rotation_rad, 1.0 * M_PI / 180);
  char why[128];
  describe_health(kidnapped.failed_checks, why, sizeof(why));
  std::printf("kidnapped frame: lost (%s); %d of %d tracked, worst %.2f mm, %.3f deg\n", why,
              v.valid, kFrames, v.worst_translation_m * 1e3, v.worst_rotation_rad * 180 / M_PI);
}

TEST(RobustTracking, AFastPanIsTrackedOrLostNeverWrong) {
  // A hand-held pan peaking at 180 deg/s at 30 Hz: 6 degrees, about 27 pixels here, a frame.
  testing::SyntheticScene scene = testing::SyntheticScene::half_resolution();
  scene.pan_peak_deg_s = 180.0;
  scene.max_depth_m = 4.0;
  constexpr int kFrames = 45;
  constexpr double kFps = 30.0;
  const std::vector<testing::SyntheticFrame>& frames = scene.render_path(kFrames, kFps);
  std::vector<SE3> truth;
  for (int i = 0; i < kFrames; ++i) truth.push_back(scene.camera_at(i / kFps));
  const Verdicts v = track_and_judge(scene, frames, truth, kFps);
  EXPECT_GE(v.valid * 10, kFrames * 9) << "tracked at least 90 % of the frames";
  EXPECT_LT(v.worst_translation_m, 0.01);
  EXPECT_LT(v.worst_rotation_rad, 1.0 * M_PI / 180);
  std::printf("pan at 180 deg/s: %d of %d tracked, %d lost, worst %.2f mm, %.3f deg\n", v.valid,
              kFrames, v.lost, v.worst_translation_m * 1e3, v.worst_rotation_rad * 180 / M_PI);
}

}  // namespace
}  // namespace rgbdtam

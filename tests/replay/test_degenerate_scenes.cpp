// Synthetic degenerate scenes: a plain corridor and a plain room, crossed at 2.4 m/s (8 cm and up
// to 1 degree a frame) with perfect depth. Frame-to-frame tracking cannot keep up; whatever it
// reports as tracked must be right (no false-valid pose), and the tracker must see that the
// depth leaves a direction free where it does.
#include <gtest/gtest.h>

#include <cmath>

#include "replay_runner.hpp"
#include "rgbdtam/core/tracker.hpp"
#include "stress_variants.hpp"
#include "synthetic_scene.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

// The tracker's own view of a scene's depth: one frame against the next.
TrackResult track_pair(const testing::SyntheticScene& scene) {
  const Params p = testing::synthetic_params(scene);
  FramePyramid frames[2];
  for (int i = 0; i < 2; ++i) {
    const testing::SyntheticFrame f = scene.render(scene.camera_at(i / 30.0));
    frames[i].allocate(scene.camera, scene.depth_factor, DepthRange{0.3, 10.0});
    ImageU16 depth;
    depth.allocate(scene.camera.width_px, scene.camera.height_px);
    for (int k = 0; k < depth.size(); ++k) {
      depth.data()[k] = f.depth[static_cast<size_t>(k)];
      frames[i].gray(0).data()[k] = f.gray[static_cast<size_t>(k)] / 255.f;
    }
    frames[i].build_gray();
    frames[i].build_inverse_depth(depth);
  }
  const TrackerOptions options = tracking_options(p);
  KeyframeBuilder builder;
  builder.allocate(scene.camera, options);
  Keyframe kf;
  builder.allocate_keyframe(&kf);
  builder.build(frames[0], 0, 0, SE3(), &kf);
  Tracker tracker;
  tracker.allocate(kf, options);
  const SE3 truth = scene.camera_at(0.0).inverse() * scene.camera_at(1 / 30.0);
  return tracker.track(kf, frames[1], truth, ReferenceScales());
}

TEST(DegenerateScenes, TheTrackerSeesWhereTheDepthLeavesADirectionFree) {
  testing::SyntheticScene corridor, room;
  corridor.layout = testing::SyntheticScene::Layout::kCorridor;
  const TrackResult along_corridor = track_pair(corridor);
  EXPECT_TRUE(along_corridor.depth_degenerate);
  // Its free direction is the corridor's axis (the camera's z, give or take the swing).
  const Vector3d axis = along_corridor.weak_direction.head<3>().normalized();
  EXPECT_GT(std::fabs(axis.z()), 0.9) << axis.transpose();
  EXPECT_FALSE(track_pair(room).depth_degenerate) << "the textured room with its box";
}

void expect_never_wrong(const std::string& layout) {
  const std::string dir = testing::make_temp_dir(("degenerate_" + layout).c_str());
  ASSERT_TRUE(testing::degenerate_sequence(dir + "/seq", layout, 90));
  const testing::ReplayOutcome out =
      testing::replay_and_evaluate(dir + "/seq", dir + "/seq/camera.conf", {"loop.enabled=false"});
  ASSERT_TRUE(out.ran);
  std::printf("%s: %u of %u frames reported tracked, %d false-valid of %d checked\n",
              layout.c_str(), out.counters.tracked, out.counters.frames,
              out.report.false_valid.count, out.report.false_valid.checked);
  EXPECT_EQ(out.report.false_valid.count, 0) << layout;
}

// Issue 23, defect 3: the smallest camera the parameters accept (40x40) runs every module,
// place recognition and the loop module's views included, where 8x8 used to pass validation and
// abort in the feature extractor.
TEST(DegenerateScenes, TheSmallestCameraAcceptedRunsEveryModule) {
  testing::SyntheticScene scene;
  scene.camera = {33.0, 33.0, 19.5, 19.5, 40, 40};
  const std::string dir = testing::make_temp_dir("smallest_camera");
  ASSERT_TRUE(testing::write_synthetic_sequence(dir, scene, 30, 30.0));
  ASSERT_TRUE(testing::write_text(dir + "/camera.conf", testing::synthetic_config(scene)));
  const std::string vocabulary =
      "loop.vocabulary=" + testing::source_path("data/vocabulary/tum-k10-l4.voc");
  const testing::ReplayOutcome out = testing::replay_and_evaluate(
      dir, dir + "/camera.conf", {vocabulary.c_str(), "map.enabled=true"});
  ASSERT_TRUE(out.ran);
  EXPECT_EQ(out.counters.frames, 30u);
  EXPECT_GT(out.loop.keyframes, 0u) << "places described at 40x40";
  EXPECT_EQ(out.report.false_valid.count, 0);
  std::printf("40x40: %u of %u frames tracked, %u places\n", out.counters.tracked,
              out.counters.frames, out.loop.keyframes);
}

TEST(DegenerateScenes, APlainCorridorIsNeverReportedWrong) { expect_never_wrong("corridor"); }
TEST(DegenerateScenes, APlainRoomIsNeverReportedWrong) { expect_never_wrong("room"); }

}  // namespace
}  // namespace rgbdtam

// The local window's measurement on the keyframe builder's thread (WindowMeasurement) is the
// tracker's own search of the same frame, moved off the tracker's core: on the rendered room,
// the same pose and information to the bit, from a copy of the keyframe taken when it is asked.
#include <gtest/gtest.h>

#include <cstring>

#include "rgbdtam/core/pose_graph.hpp"
#include "rgbdtam/runtime/tracking/pose_search.hpp"
#include "rgbdtam/runtime/tracking/window_measurement.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

TEST(WindowMeasurement, TheBuildersMeasurementIsTheTrackersSearchFromACopyOfTheKeyframe) {
  const testing::SyntheticScene room = testing::SyntheticScene::half_resolution();
  Params p = testing::synthetic_params(room);
  p.tracker = tracking_options(p);
  p.health = health_limits(p);
  p.loop.enabled = true;
  p.loop.window = true;
  FramePyramid keyframe_frame, frame;
  testing::synthetic_pyramid(room.render(SE3()), p, &keyframe_frame);
  const SE3 T_w_c(Eigen::Quaterniond(Eigen::AngleAxisd(0.02, Vector3d::UnitY())),
                  Vector3d(0.04, 0.01, 0.0));
  testing::synthetic_pyramid(room.render(T_w_c), p, &frame);
  KeyframeBuilder builder;
  builder.allocate(p.camera, p.tracker);
  Keyframe kf;
  builder.allocate_keyframe(&kf);
  builder.build(keyframe_frame, 7, 0, SE3(), &kf);

  // The tracker's side: the frame's pose is out (its motion has it), and a guess 5 mm off.
  constexpr int64_t kT = 100'000'000;
  MotionState motion;
  motion.init(true, 0);
  motion.begin(SE3(), 0);
  motion.track(T_w_c, kT, true);
  PoseSearch search;
  search.allocate(kf, p.tracker, p.health, alias_range_m(p));
  const SE3 guess = T_w_c * SE3(Eigen::Quaterniond::Identity(), Vector3d(0.005, 0.0, 0.0));
  const Attempt tracker_side = search.track(&kf, frame, guess, motion, kT);
  ASSERT_EQ(tracker_side.failed, 0u);

  // The builder's side: ordered while the keyframe is as it was, which then changes; measured
  // on the frame rebuilt from its level 0, as the builder has it.
  WindowMeasurement window;
  window.allocate(p, builder);
  window.order({&kf, guess, motion, search.typical_scales(), kT});
  for (int l = 0; l < kPyramidLevels; ++l) {
    kf.photometric_sets[0][l].clear();
    kf.geometric[l].clear();
  }
  FramePyramid builders;
  builders.allocate(p.camera, p.sensor.depth_factor, p.sensor.depth_range);
  const size_t pixels = static_cast<size_t>(frame.gray(0).size());
  std::memcpy(builders.gray(0).data(), frame.gray(0).data(), sizeof(float) * pixels);
  std::memcpy(builders.inverse_depth_level0().data(), frame.inverse_depth(0).data(),
              sizeof(float) * pixels);
  builders.build_gray();
  builders.build_inverse_depth_levels();
  window.measure(builders);

  ASSERT_TRUE(window.ordered());
  const KeyframeLink& link = window.link();
  EXPECT_EQ(link.kind, EdgeKind::kCovisible);
  EXPECT_EQ(link.reference_id, 7u);
  EXPECT_EQ(link.T_reference_keyframe.matrix(), tracker_side.r.T_k_c.matrix());
  EXPECT_EQ(link.information, graph_information(tracker_side.r.information / p.covariance_scale,
                                                tracker_side.r.T_k_c));
  EXPECT_LT((link.T_reference_keyframe.translation() - T_w_c.translation()).norm(), 1e-3);

  // Nothing asked: nothing measured.
  window.order(WindowRequest());
  window.measure(builders);
  EXPECT_FALSE(window.ordered());
  EXPECT_EQ(window.link().kind, EdgeKind::kRestart);
}

}  // namespace
}  // namespace rgbdtam

// The local window's measurements on the keyframe builder's thread (WindowMeasurement) are the
// tracker's own search of the same frame, moved off the tracker's core: on the rendered room,
// the same poses and information to the bit, from copies of the keyframes taken when asked.
#include <gtest/gtest.h>

#include <cstring>

#include "rgbdtam/core/pose_graph.hpp"
#include "rgbdtam/runtime/tracking/pose_search.hpp"
#include "rgbdtam/runtime/tracking/window_measurement.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

TEST(WindowMeasurement, TheBuildersMeasurementsAreTheTrackersSearchFromCopiesOfTheKeyframes) {
  const testing::SyntheticScene room = testing::SyntheticScene::half_resolution();
  Params p = testing::synthetic_params(room);
  p.tracker = tracking_options(p);
  p.health = health_limits(p);
  p.loop.enabled = true;
  p.loop.window = true;
  p.loop.window_keyframes = 2;
  // Two earlier keyframes, on either side of the frame.
  const SE3 T_w_k[2] = {SE3(), SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.03, Vector3d::UnitY())),
                                   Vector3d(0.07, 0.0, 0.01))};
  const uint32_t ids[2] = {7, 9};
  KeyframeBuilder builder;
  builder.allocate(p.camera, p.tracker);
  Keyframe kfs[2];
  for (int i = 0; i < 2; ++i) {
    FramePyramid keyframe_frame;
    testing::synthetic_pyramid(room.render(T_w_k[i]), p, &keyframe_frame);
    builder.allocate_keyframe(&kfs[i]);
    builder.build(keyframe_frame, ids[i], 0, T_w_k[i], &kfs[i]);
  }
  FramePyramid frame;
  const SE3 T_w_c(Eigen::Quaterniond(Eigen::AngleAxisd(0.02, Vector3d::UnitY())),
                  Vector3d(0.04, 0.01, 0.0));
  testing::synthetic_pyramid(room.render(T_w_c), p, &frame);

  // The tracker's side: the frame's pose is out (its motion has it), and a guess 5 mm off.
  constexpr int64_t kT = 100'000'000;
  MotionState motion;
  motion.init(true, 0);
  motion.begin(SE3(), 0);
  motion.track(T_w_c, kT, true);
  PoseSearch search;
  search.allocate(kfs[0], p.tracker, p.health, alias_range_m(p));
  const SE3 guess = T_w_c * SE3(Eigen::Quaterniond::Identity(), Vector3d(0.005, 0.0, 0.0));
  const ReferenceScales typical = search.typical_scales();
  Attempt tracker_side[2];
  for (int i = 0; i < 2; ++i) {
    search.use_scales(typical);
    tracker_side[i] = search.track(&kfs[i], frame, guess, motion, kT);
    ASSERT_EQ(tracker_side[i].failed, 0u);
  }

  // The builder's side: ordered while the keyframes are as they were, which then change;
  // measured on the frame rebuilt from its level 0, as the builder has it.
  WindowMeasurement window;
  window.allocate(p, builder);
  ASSERT_EQ(window.capacity(), 2);
  WindowRequest request;
  request.references[0] = &kfs[0];
  request.references[1] = &kfs[1];
  request.count = 2;
  request.T_w_c = guess;
  request.motion = motion;
  request.typical = typical;
  request.t_ns = kT;
  window.order(request);
  for (Keyframe& kf : kfs) {
    for (int l = 0; l < kPyramidLevels; ++l) {
      kf.photometric_sets[0][l].clear();
      kf.geometric[l].clear();
    }
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

  const WindowLinks& links = window.links();
  ASSERT_EQ(links.count, 2);
  for (int i = 0; i < 2; ++i) {
    const KeyframeLink& link = links.link[i];
    const TrackResult& r = tracker_side[i].r;
    EXPECT_EQ(link.kind, EdgeKind::kCovisible);
    EXPECT_EQ(link.reference_id, ids[i]);
    EXPECT_EQ(link.T_reference_keyframe.matrix(), r.T_k_c.matrix());
    EXPECT_EQ(link.information, graph_information(r.information / p.covariance_scale, r.T_k_c));
    const SE3 truth = T_w_k[i].inverse() * T_w_c;
    EXPECT_LT((link.T_reference_keyframe.translation() - truth.translation()).norm(), 1e-3);
  }

  // Nothing asked: nothing measured.
  window.order(WindowRequest());
  window.measure(builders);
  EXPECT_EQ(window.links().count, 0);
}

}  // namespace
}  // namespace rgbdtam

// A keyframe's aliases: where its image matches itself shifted along the surfaces it sees.
#include <gtest/gtest.h>

#include <cmath>

#include "repeated_scene.hpp"
#include "rgbdtam/core/keyframe_aliases.hpp"
#include "rgbdtam/core/tracking_health.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

// The keyframe of one frame, and that frame.
struct OwnKeyframe {
  OwnKeyframe(const testing::SyntheticFrame& f, const PinholeIntrinsics& camera,
              double depth_factor) {
    testing::SyntheticScene like;
    like.camera = camera;
    like.depth_factor = depth_factor;
    p = testing::synthetic_params(like);
    p.tracker = tracking_options(p);
    testing::synthetic_pyramid(f, p, &own);
    KeyframeBuilder builder;
    builder.allocate(p.camera, p.tracker);
    builder.allocate_keyframe(&kf);
    builder.build(own, 0, 0, SE3(), &kf);
  }
  KeyframeAliases aliases(double range_m) const {
    KeyframeAliasFinder finder;
    finder.allocate(kf, p.tracker);
    KeyframeAliases out;
    finder.find(own, kf, range_m, &out);
    return out;
  }
  Params p;
  FramePyramid own;
  Keyframe kf;
};

// The keyframe of frame 0 and its aliases within range_m.
KeyframeAliases aliases_of(const testing::SyntheticFrame& f, const PinholeIntrinsics& camera,
                           double depth_factor, double range_m) {
  return OwnKeyframe(f, camera, depth_factor).aliases(range_m);
}

testing::RepeatedScene tiled_wall() {
  // 15 cm tiles 60 cm away, at half resolution.
  testing::RepeatedScene tiles;
  EXPECT_TRUE(testing::RepeatedScene::named("tiles15_d06_10hz_noisy", &tiles));
  tiles.camera = testing::SyntheticScene::half_resolution().camera;
  return tiles;
}

TEST(KeyframeAliases, ATiledWallRepeatsOneTileAwayAlongTheWallAndATexturedRoomDoesNot) {
  const testing::RepeatedScene tiles = tiled_wall();
  const KeyframeAliases a = aliases_of(tiles.render(0), tiles.camera, tiles.depth_factor, 0.6);
  ASSERT_GT(a.count, 0);
  // Every alias is a whole number of tiles along the wall (the first camera's x).
  bool one_tile = false;
  for (int i = 0; i < a.count; ++i) {
    const Vector3d& s = a.shift_k[i];
    const double tiles_along = s.norm() / 0.15;
    EXPECT_NEAR(tiles_along, std::round(tiles_along), 0.1) << s.transpose();
    one_tile = one_tile || std::fabs(s.norm() - 0.15) < 0.01;
  }
  EXPECT_TRUE(one_tile) << "the nearest alias, one tile away, is found";
  // The textured room with its box: nothing repeats.
  const testing::SyntheticScene room = testing::SyntheticScene::half_resolution();
  EXPECT_EQ(aliases_of(room.render(SE3()), room.camera, room.depth_factor, 0.6).count, 0);
}

TEST(KeyframeAliases, TheCoarseLevelsKeepACandidateOnAnAliasOnItsOwnMinimum) {
  // What lets the pose search spare the finer levels a candidate the coarse ones bring back to
  // the pose (Tracker::align): one on a true alias stays there.
  const testing::RepeatedScene tiles = tiled_wall();
  const OwnKeyframe k(tiles.render(0), tiles.camera, tiles.depth_factor);
  const KeyframeAliases a = k.aliases(0.6);
  ASSERT_GT(a.count, 0);
  Tracker tracker;
  tracker.allocate(k.kf, k.p.tracker);
  constexpr int kProbingLevel = 2;
  for (int i = 0; i < a.count; ++i) {
    const SE3 candidate(Eigen::Quaterniond::Identity(), a.shift_k[i]);
    const SE3 aligned = tracker.align(k.kf, k.own, candidate, kAllTerms, kProbingLevel);
    EXPECT_FALSE(same_pose(aligned, SE3())) << a.shift_k[i].transpose();
    EXPECT_TRUE(same_pose(aligned, candidate)) << a.shift_k[i].transpose();
  }
}

}  // namespace
}  // namespace rgbdtam

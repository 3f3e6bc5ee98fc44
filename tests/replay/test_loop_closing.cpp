// Loop closure and relocalisation: the light keyframe store, the loop module on a synthetic
// loop with known drift, and place recognition that never accepts an unrelated place.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "config_files.hpp"
#include "frontend_frames.hpp"
#include "rgbdtam/runtime/loop_closing.hpp"
#include "synthetic_scene.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

constexpr double kDeg = M_PI / 180.0;

int64_t no_clock() { return 0; }

const Vocabulary& shipped_vocabulary() {
  static Vocabulary v;
  static bool loaded = false;
  if (!loaded) {
    Params p;
    const std::string path = testing::source_path("data/vocabulary/tum-k10-l4.voc");
    std::snprintf(p.loop.vocabulary, sizeof(p.loop.vocabulary), "%s", path.c_str());
    Status error;
    loaded = load_vocabulary(p, &v, &error);
    EXPECT_TRUE(loaded) << error.message();
  }
  return v;
}

// A view as the tracker hands it to the loop module.
void fill_keyframe(const FramePyramid& frame, LoopKeyframe* kf) {
  std::copy(frame.gray(0).data(), frame.gray(0).data() + kf->gray.size(), kf->gray.data());
  std::copy(frame.inverse_depth(0).data(), frame.inverse_depth(0).data() + kf->gray.size(),
            kf->inverse_depth.data());
}

void render_into(const testing::SyntheticScene& scene, const SE3& T_w_c, FramePyramid* frame) {
  const testing::SyntheticFrame f = scene.render(T_w_c);
  ImageU16 depth;
  depth.allocate(scene.camera.width_px, scene.camera.height_px);
  for (int i = 0; i < depth.size(); ++i) {
    depth.data()[i] = f.depth[static_cast<size_t>(i)];
    frame->gray(0).data()[i] = f.gray[static_cast<size_t>(i)] / 255.f;
  }
  frame->build_inverse_depth(depth);
}

TEST(PlaceStore, AFullStoreForgetsTheOldestAndItsHandlesGoStale) {
  PlaceStore store;
  store.allocate(4, 8, 16);
  PlaceHandle first;
  for (uint32_t id = 0; id < 6; ++id) {
    PlaceRecord* r = store.begin_insert();
    r->keyframe_id = id * 10;
    ASSERT_TRUE(r->bow.push_back({id, 1.f}));
    store.commit();
    if (id == 0) first = store.handle(0);
  }
  EXPECT_EQ(store.size(), 4);
  EXPECT_EQ(store.evicted(), 2u);
  EXPECT_EQ(store.get(first), nullptr) << "its slot holds another keyframe now";
  EXPECT_EQ(store.in_order(0).keyframe_id, 20u);
  EXPECT_EQ(store.order_of(50), 3);
  EXPECT_EQ(store.order_of(10), -1);
  EXPECT_EQ(store.order_of(25), -1);
  ASSERT_NE(store.get(store.handle(3)), nullptr);
  EXPECT_EQ(store.get(store.handle(3))->keyframe_id, 50u);
  // The forgotten places are out of the index too.
  BowVector q;
  q.reserve_once(1);
  ASSERT_TRUE(q.push_back({0, 1.f}));
  PlaceMatch m[4];
  EXPECT_EQ(store.database().query(q, nullptr, nullptr, m, 4), 0);
}

// The camera glides 60 cm to the side of the synthetic room and back, one keyframe a second;
// its odometry turns 1 degree too far and slides 1 cm at every step.
TEST(LoopModule, ASyntheticLoopWithKnownDriftIsFoundAndMostOfTheDriftRemoved) {
  // Half resolution: 25 rendered keyframes, cheap enough under qemu.
  const testing::SyntheticScene scene = testing::SyntheticScene::half_resolution();
  Params p = testing::synthetic_params(scene);
  p.loop.min_age_s = 4.0;
  const Vocabulary& voc = shipped_vocabulary();
  PlaceStore store;
  store.allocate(64, p.loop.features, voc.words());
  CorrectionQueue corrections;
  corrections.allocate(2, 64);
  LoopModule loop;
  ASSERT_TRUE(loop.init(p, &voc, &store, &corrections, no_clock).is_ok());
  LoopKeyframe kf;
  kf.gray.allocate(scene.camera.width_px, scene.camera.height_px);
  kf.inverse_depth.allocate(scene.camera.width_px, scene.camera.height_px);
  FramePyramid frame;
  frame.allocate(scene.camera, scene.depth_factor, DepthRange{0.3, 10.0});

  const SE3 start = testing::SyntheticScene::pose_at(0.0);
  std::vector<SE3> truth;
  for (int i = 0; i <= 24; ++i) {
    const double x = 0.05 * (i <= 12 ? i : 24 - i);
    truth.push_back(start * SE3(Eigen::Quaterniond::Identity(), Vector3d(x, 0, 0)));
  }
  const SE3 bias(so3_exp(Vector3d(0, 1.0 * kDeg, 0)), Vector3d(0.01, 0, 0));
  SE3 drifted = truth[0];
  double drift_before = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    if (i > 0) drifted = drifted * (truth[i - 1].inverse() * truth[i]) * bias;
    drift_before = std::max(drift_before, (drifted.translation() - truth[i].translation()).norm());
    render_into(scene, truth[i], &frame);
    fill_keyframe(frame, &kf);
    kf.keyframe_id = static_cast<uint32_t>(i);
    kf.reference_id = i > 0 ? static_cast<uint32_t>(i - 1) : 0;
    kf.timestamp_ns = static_cast<int64_t>(i) * 1'000'000'000;
    kf.T_w_k = drifted;
    kf.information = 1e4 * Matrix6d::Identity();
    kf.corrections_adopted = loop.counters().corrections;  // adopted at once, as in replay
    // Once corrected, the next keyframe continues from its corrected predecessor.
    if (loop.counters().corrections > 0 && i > 0) {
      kf.T_w_k =
          store.in_order(store.size() - 1).T_w_k * (truth[i - 1].inverse() * truth[i]) * bias;
      drifted = kf.T_w_k;
    }
    loop.step(kf);
    while (corrections.front() != nullptr) corrections.pop();
  }
  double drift_after = 0;
  for (int i = 0; i < store.size(); ++i) {
    const PlaceRecord& r = store.in_order(i);
    drift_after =
        std::max(drift_after, (r.T_w_k.translation() - truth[r.keyframe_id].translation()).norm());
  }
  const LoopCounters& c = loop.counters();
  std::printf(
      "drift %.1f cm before, %.1f cm after; %u candidates, %u verified, %u loops, %u "
      "corrections\n",
      100 * drift_before, 100 * drift_after, c.candidates, c.verified, c.loops, c.corrections);
  EXPECT_GE(c.loops, 1u);
  EXPECT_GE(c.corrections, 1u);
  EXPECT_GT(drift_before, 0.05);
  EXPECT_LT(drift_after, 0.5 * drift_before);
}

// A view described as the loop module describes a keyframe.
struct DescribedView {
  std::vector<Feature> features;
  std::vector<BowEntry> bow;
};

DescribedView describe(PlaceRecognizer* recognizer, const FramePyramid& f, const Vocabulary& voc) {
  recognizer->describe(f.gray(0), f.inverse_depth(0), f.intrinsics(0), voc);
  return {{recognizer->features().begin(), recognizer->features().end()},
          {recognizer->bow().begin(), recognizer->bow().end()}};
}

void remember(const DescribedView& v, uint32_t id, PlaceStore* store) {
  PlaceRecord* r = store->begin_insert();
  r->keyframe_id = id;
  for (const Feature& f : v.features) ASSERT_TRUE(r->features.push_back(f));
  for (const BowEntry& e : v.bow) ASSERT_TRUE(r->bow.push_back(e));
  store->commit();
}

// Keyframes of the real clip against the synthetic room, both ways: no place of one is a
// place of the other, so nothing may be verified.
TEST(PlaceRecognition, UnrelatedPlacesAreRejected) {
  const testing::SyntheticScene scene;
  const Params p = testing::synthetic_params(scene);
  const Vocabulary& voc = shipped_vocabulary();
  const VerificationLimits limits = VerificationLimits::of(p);
  PlaceRecognizer recognizer;
  recognizer.allocate(p);

  Params clip_params;
  ASSERT_TRUE(
      read_params_file(testing::source_path("config/tum_fr1.conf").c_str(), &clip_params).is_ok());
  FrontendFrames frames;
  ASSERT_TRUE(
      frames.open(testing::source_path("data/tum_fr1_xyz_clip").c_str(), clip_params).is_ok());
  std::vector<DescribedView> clip, room;
  for (int i = 0; i < frames.count(); i += 7) {
    ASSERT_TRUE(frames.load(i));
    clip.push_back(describe(&recognizer, frames.frame(), voc));
  }
  FramePyramid frame;
  frame.allocate(scene.camera, scene.depth_factor, DepthRange{0.3, 10.0});
  for (int i = 0; i < 8; ++i) {
    render_into(scene, testing::SyntheticScene::pose_at(0.3 * i), &frame);
    room.push_back(describe(&recognizer, frame, voc));
  }

  int checked = 0;
  auto expect_none_verified = [&](const std::vector<DescribedView>& places,
                                  const std::vector<DescribedView>& queries) {
    PlaceStore store;
    store.allocate(16, p.loop.features, voc.words());
    for (size_t i = 0; i < places.size(); ++i)
      remember(places[i], static_cast<uint32_t>(i), &store);
    FixedVector<Feature> features;
    features.reserve_once(p.loop.features);
    for (const DescribedView& q : queries) {
      features.clear();
      for (const Feature& f : q.features) ASSERT_TRUE(features.push_back(f));
      for (int i = 0; i < store.size(); ++i) {
        EXPECT_EQ(recognizer.verify(features, store.in_order(i), limits).inliers, 0)
            << "a wrong place passed";
        ++checked;
      }
    }
  };
  expect_none_verified(room, clip);
  expect_none_verified(clip, room);
  EXPECT_EQ(checked, 2 * static_cast<int>(room.size() * clip.size()));
  // ... while a place does find itself again, so the rejections mean something.
  PlaceStore store;
  store.allocate(2, p.loop.features, voc.words());
  remember(clip[0], 0, &store);
  ASSERT_TRUE(
      frames.open(testing::source_path("data/tum_fr1_xyz_clip").c_str(), clip_params).is_ok());
  ASSERT_TRUE(frames.load(3));
  recognizer.describe(frames.frame().gray(0), frames.frame().inverse_depth(0),
                      frames.frame().intrinsics(0), voc);
  EXPECT_GE(recognizer.verify(store.in_order(0), limits).inliers, limits.min_inliers);
}

}  // namespace
}  // namespace rgbdtam

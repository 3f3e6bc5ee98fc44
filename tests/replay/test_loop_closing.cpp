// Loop closure and relocalisation: the light keyframe store, the loop module on a synthetic
// loop with known drift, its covisible and reuse edges, relocalisation, and verification that
// never accepts an unrelated place.
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <vector>

#include "config_files.hpp"
#include "frontend_frames.hpp"
#include "measures.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/runtime/loop_closing.hpp"
#include "rgbdtam/runtime/relocaliser.hpp"
#include "synthetic_scene.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

using testing::kDeg;

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
  capture_view(frame, &kf->view);
}

void render_into(const testing::SyntheticScene& scene, const SE3& T_w_c, FramePyramid* frame) {
  const testing::SyntheticFrame f = scene.render(T_w_c);
  ImageU16 depth;
  depth.allocate(scene.camera.width_px, scene.camera.height_px);
  for (int i = 0; i < depth.size(); ++i) {
    depth.data()[i] = f.depth[static_cast<size_t>(i)];
    frame->gray(0).data()[i] = f.gray[static_cast<size_t>(i)] / 255.f;
  }
  frame->build_gray();
  frame->build_inverse_depth(depth);
}

// The loop module with its store and queue on a synthetic scene, fed keyframes as the tracker
// would: each measured against its predecessor with the given relative pose.
struct LoopFixture {
  explicit LoopFixture(const testing::SyntheticScene& s, int places = 64,
                       double max_drift_ratio = Params().loop.max_drift_ratio,
                       double min_window_correction_m = Params().loop.min_window_correction_m)
      : scene(s) {
    params = testing::synthetic_params(scene);
    params.loop.max_drift_ratio = max_drift_ratio;
    params.loop.min_window_correction_m = min_window_correction_m;
    store.allocate(places, params.loop.features, shipped_vocabulary().words(), scene.camera);
    corrections.allocate(2, places);
    EXPECT_TRUE(loop.init(params, &shipped_vocabulary(), &store, &corrections, no_clock).is_ok());
    kf.gray.allocate(scene.camera.width_px, scene.camera.height_px);
    kf.inverse_depth.allocate(scene.camera.width_px, scene.camera.height_px);
    kf.view.allocate(scene.camera);
    frame.allocate(scene.camera, scene.depth_factor, DepthRange{0.3, 10.0});
  }
  // A keyframe seen at T_w_true, believed at T_w_k, measured from the previous one (and from
  // the window's keyframes too: the tracker's local window).
  void keyframe(uint32_t id, const SE3& T_w_true, const SE3& T_w_k, const SE3& T_previous_k,
                std::initializer_list<WindowEdge> window = {}) {
    render_into(scene, T_w_true, &frame);
    fill_keyframe(frame, &kf);
    kf.kind = LoopKeyframe::Kind::kKeyframe;
    kf.keyframe_id = id;
    kf.reference_id = id > 0 ? id - 1 : 0;
    kf.reference_edge = id > 0 ? EdgeKind::kOdometry : EdgeKind::kRestart;
    kf.timestamp_ns = static_cast<int64_t>(id) * 1'000'000'000;
    kf.T_w_k = T_w_k;
    kf.T_reference_keyframe = T_previous_k;
    kf.information = 1e4 * Matrix6d::Identity();
    kf.window_edges = 0;
    for (const WindowEdge& w : window) kf.window[kf.window_edges++] = w;
    kf.corrections_adopted = loop.counters().corrections;  // adopted at once, as in replay
    loop.step(kf);
    while (corrections.front() != nullptr) corrections.pop();
  }
  testing::SyntheticScene scene;
  Params params;
  PlaceStore store;
  CorrectionQueue corrections;
  LoopModule loop;
  LoopKeyframe kf;
  FramePyramid frame;
};

struct EdgeRecorder : LoopObserver {
  std::vector<GraphEdgeEvent> edges;
  void on_edge(const GraphEdgeEvent& e) override { edges.push_back(e); }
  int count(EdgeKind kind) const {
    int n = 0;
    for (const GraphEdgeEvent& e : edges) n += e.kind == kind;
    return n;
  }
};

TEST(PlaceStore, AFullStoreForgetsTheOldestAndItsHandlesGoStale) {
  PlaceStore store;
  store.allocate(4, 8, 16, testing::SyntheticScene::half_resolution().camera);
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
  EXPECT_EQ(store.stale_lookups(), 0u);
  EXPECT_EQ(store.get(first), nullptr) << "its slot holds another keyframe now";
  EXPECT_EQ(store.stale_lookups(), 1u) << "a refused lookup is counted";
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
  // Half resolution: 25 rendered keyframes, cheap enough under qemu. The injected drift, 27 cm
  // over 1.2 m, is twenty times a real tracker's: the look-alike gate is opened for it.
  LoopFixture f(testing::SyntheticScene::half_resolution(), 64, 0.5);
  EdgeRecorder edges;
  f.loop.set_observer(&edges);
  const SE3 start = testing::SyntheticScene::pose_at(0.0);
  std::vector<SE3> truth;
  for (int i = 0; i <= 24; ++i) {
    const double x = 0.05 * (i <= 12 ? i : 24 - i);
    truth.push_back(start * SE3(Eigen::Quaterniond::Identity(), Vector3d(x, 0, 0)));
  }
  const SE3 bias(so3_exp(Vector3d(0, 1.0 * kDeg, 0)), Vector3d(0.01, 0, 0));
  SE3 believed = truth[0];
  double drift_before = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    const SE3 step = i > 0 ? (truth[i - 1].inverse() * truth[i]) * bias : SE3();
    // Once corrected, the next keyframe continues from its corrected predecessor.
    if (i > 0) believed = f.store.in_order(f.store.size() - 1).T_w_k * step;
    drift_before = std::max(drift_before, (believed.translation() - truth[i].translation()).norm());
    f.keyframe(static_cast<uint32_t>(i), truth[i], believed, step);
  }
  double drift_after = 0;
  for (int i = 0; i < f.store.size(); ++i) {
    const PlaceRecord& r = f.store.in_order(i);
    drift_after =
        std::max(drift_after, (r.T_w_k.translation() - truth[r.keyframe_id].translation()).norm());
  }
  const LoopCounters& c = f.loop.counters();
  std::printf(
      "drift %.1f cm before, %.1f cm after; %u views aligned, %u revisit and %u covisible "
      "edges, %u corrections\n",
      100 * drift_before, 100 * drift_after, c.candidates, c.revisit_edges, c.covisible_edges,
      c.corrections);
  EXPECT_GE(c.revisit_edges, 1u);
  EXPECT_GE(c.corrections, 1u);
  EXPECT_GT(drift_before, 0.05);
  EXPECT_LT(drift_after, 0.5 * drift_before);
  // Every edge the graph took is right: within 1 cm and 0.5 degrees of the true relative pose
  // (odometry edges carry the bias by construction: 1 cm and 1 degree).
  for (const GraphEdgeEvent& e : edges.edges) {
    if (e.kind == EdgeKind::kOdometry) continue;
    const SE3 error = (truth[e.from_id].inverse() * truth[e.to_id]).inverse() * e.T_from_to;
    EXPECT_LT(error.translation().norm(), 0.01) << edge_kind_name(e.kind) << " edge";
    EXPECT_LT(so3_log(error.quaternion()).norm(), 0.5 * kDeg) << edge_kind_name(e.kind) << " edge";
  }
}

// Keyframes a few centimetres apart along a short path: each is aligned with a neighbour the
// graph reaches in a few edges (covisible), and none of them counts as a revisit.
TEST(LoopModule, NeighboursAreCovisibleEdgesNotRevisits) {
  LoopFixture f(testing::SyntheticScene::half_resolution());
  EdgeRecorder edges;
  f.loop.set_observer(&edges);
  const SE3 start = testing::SyntheticScene::pose_at(0.0);
  for (uint32_t i = 0; i < 6; ++i) {
    const SE3 T = start * SE3(Eigen::Quaterniond::Identity(), Vector3d(0.03 * i, 0, 0));
    const SE3 step(Eigen::Quaterniond::Identity(), Vector3d(i > 0 ? 0.03 : 0.0, 0, 0));
    f.keyframe(i, T, T, step);
  }
  EXPECT_EQ(edges.count(EdgeKind::kOdometry), 5);
  EXPECT_GE(edges.count(EdgeKind::kCovisible), 3);
  EXPECT_EQ(edges.count(EdgeKind::kRevisit), 0);
  EXPECT_EQ(f.loop.counters().corrections, 0u) << "the map agreed with every edge";
}

// The tracker left keyframe 5 for keyframe 0 (map reuse): the frame both tracked ties them. The
// map, drifted, put them 6 cm further apart than that measurement says: the edge corrects it.
TEST(LoopModule, TheTrackersReuseOfAnEarlierKeyframeIsAnEdgeThatCorrectsTheMap) {
  LoopFixture f(testing::SyntheticScene::half_resolution());
  EdgeRecorder edges;
  f.loop.set_observer(&edges);
  const SE3 start = testing::SyntheticScene::pose_at(0.0);
  const SE3 drift(Eigen::Quaterniond::Identity(), Vector3d(0.012, 0, 0));
  SE3 believed = start;
  for (uint32_t i = 0; i < 6; ++i) {
    const SE3 T = start * SE3(so3_exp(Vector3d(0, 0.1 * i, 0)), Vector3d::Zero());  // turning
    const SE3 step =
        i > 0 ? (start * SE3(so3_exp(Vector3d(0, 0.1 * (i - 1), 0)), Vector3d::Zero())).inverse() *
                    T * drift
              : SE3();
    if (i > 0) believed = believed * step;
    f.keyframe(i, T, believed, step);
  }
  LoopKeyframe& reuse = f.kf;
  reuse.kind = LoopKeyframe::Kind::kReuse;
  reuse.keyframe_id = 0;
  reuse.reference_id = 5;
  reuse.reference_edge = EdgeKind::kReuse;
  const SE3 truth_5 = start * SE3(so3_exp(Vector3d(0, 0.5, 0)), Vector3d::Zero());
  reuse.T_reference_keyframe = truth_5.inverse() * start;
  reuse.information = 1e6 * Matrix6d::Identity();
  const double before = (f.store.in_order(5).T_w_k.translation() - truth_5.translation()).norm();
  f.loop.step(reuse);
  const double after = (f.store.in_order(5).T_w_k.translation() - truth_5.translation()).norm();
  EXPECT_EQ(f.loop.counters().reuse_edges, 1u);
  EXPECT_EQ(edges.count(EdgeKind::kReuse), 1);
  EXPECT_EQ(f.loop.counters().corrections, 1u);
  EXPECT_GT(before, 0.05);
  EXPECT_LT(after, 0.2 * before);
}

// Keyframes 0..n-1 fed at truth(i), each measured from the one before with the odometry's drift
// appended; keyframe n's believed pose and its measured step, not yet fed.
struct Drifted {
  SE3 believed;
  SE3 step;
};
template <typename Truth>
Drifted feed_drifting(LoopFixture* f, uint32_t n, const Truth& truth, const SE3& drift) {
  SE3 believed = truth(0);
  for (uint32_t i = 0; i < n; ++i) {
    const SE3 step = i > 0 ? truth(i - 1).inverse() * truth(i) * drift : SE3();
    if (i > 0) believed = believed * step;
    f->keyframe(i, truth(i), believed, step);
  }
  const SE3 step = truth(n - 1).inverse() * truth(n) * drift;
  return {believed * step, step};
}

// The local window (issue 33): keyframe 4 is measured again against keyframe 2, as the tracker
// measures it against keyframe 3. Odometry drifted 4 mm a step: less than a revisit corrects
// (2 cm), more than the window refines from (2 mm). The second measurement refines the map and
// the correction is sent; with the window's limit as large as a revisit's, nothing moves.
TEST(LoopModule, TheWindowsSecondMeasurementRefinesTheMapBelowTheRevisitLimit) {
  const SE3 start = testing::SyntheticScene::pose_at(0.0);
  auto truth = [&](uint32_t i) {
    return start * SE3(so3_exp(Vector3d(0, 0.1 * i, 0)), Vector3d::Zero());
  };
  const SE3 drift(Eigen::Quaterniond::Identity(), Vector3d(0.004, 0, 0));
  for (const double limit_m :
       {Params().loop.min_window_correction_m, Params().loop.min_correction_m}) {
    LoopFixture f(testing::SyntheticScene::half_resolution(), 64, Params().loop.max_drift_ratio,
                  limit_m);
    const Drifted k4 = feed_drifting(&f, 4, truth, drift);
    const double before = (k4.believed.translation() - truth(4).translation()).norm();
    ASSERT_EQ(f.loop.counters().corrections, 0u) << "the drift is below a revisit's limit";
    f.keyframe(4, truth(4), k4.believed, k4.step,
               {{2, truth(2).inverse() * truth(4), 1e4 * Matrix6d::Identity()}});
    const double after = (f.store.in_order(4).T_w_k.translation() - truth(4).translation()).norm();
    std::printf("window limit %.0f mm: keyframe 4 %.1f mm from the truth before, %.1f after\n",
                1000 * limit_m, 1000 * before, 1000 * after);
    EXPECT_EQ(f.loop.counters().window_edges, 1u);
    EXPECT_GT(before, 0.01);
    if (limit_m < 0.01) {
      EXPECT_EQ(f.loop.counters().corrections, 1u);
      EXPECT_LT(after, 0.8 * before);
    } else {
      EXPECT_EQ(f.loop.counters().corrections, 0u);
      EXPECT_NEAR(after, before, 1e-9);
    }
  }
}

// The window measures a keyframe against several earlier ones (loop.window_keyframes): keyframe
// 5 against keyframes 2 and 3, as the tracker measures it against 4. Each measurement is an edge
// of its own, and the two take the drift out of keyframe 5 further than the nearer one alone.
TEST(LoopModule, EachOfTheWindowsMeasurementsIsAnEdge) {
  const SE3 start = testing::SyntheticScene::pose_at(0.0);
  auto truth = [&](uint32_t i) {
    return start * SE3(so3_exp(Vector3d(0, 0.08 * i, 0)), Vector3d::Zero());
  };
  const SE3 drift(Eigen::Quaterniond::Identity(), Vector3d(0.004, 0, 0));
  const WindowEdge from_3{3, truth(3).inverse() * truth(5), 1e4 * Matrix6d::Identity()};
  const WindowEdge from_2{2, truth(2).inverse() * truth(5), 1e4 * Matrix6d::Identity()};
  double after[2] = {0.0, 0.0};
  for (int edges = 1; edges <= 2; ++edges) {
    LoopFixture f(testing::SyntheticScene::half_resolution());
    const Drifted k5 = feed_drifting(&f, 5, truth, drift);
    const double before = (k5.believed.translation() - truth(5).translation()).norm();
    ASSERT_EQ(f.loop.counters().corrections, 0u) << "the drift is below a revisit's limit";
    if (edges == 1) {
      f.keyframe(5, truth(5), k5.believed, k5.step, {from_3});
    } else {
      f.keyframe(5, truth(5), k5.believed, k5.step, {from_3, from_2});
    }
    EXPECT_EQ(f.loop.counters().window_edges, static_cast<uint32_t>(edges));
    after[edges - 1] = (f.store.in_order(5).T_w_k.translation() - truth(5).translation()).norm();
    std::printf("%d window edges: keyframe 5 %.1f mm from the truth before, %.1f after\n", edges,
                1000 * before, 1000 * after[edges - 1]);
    EXPECT_LT(after[edges - 1], before);
  }
  EXPECT_LT(after[1], after[0]);
}

// Keyframes of the real clip against the synthetic room, both ways: no place of one is a
// place of the other, so no view alignment may show the same place, from the place's own pose
// or a guess turned and shifted from it; while the clip's own views do find each other, so the
// rejections mean something.
TEST(PlaceRecognition, UnrelatedPlacesAreRejected) {
  const testing::SyntheticScene scene;
  Params clip_params;
  ASSERT_TRUE(
      read_params_file(testing::source_path("config/tum_fr1.conf").c_str(), &clip_params).is_ok());
  FrontendFrames frames;
  ASSERT_TRUE(
      frames.open(testing::source_path("data/tum_fr1_xyz_clip").c_str(), clip_params).is_ok());
  std::vector<View> clip, room;
  for (int i = 0; i < frames.count(); i += 7) {
    if (!frames.load(i)) continue;
    clip.emplace_back();
    clip.back().allocate(clip_params.camera);
    capture_view(frames.frame(), &clip.back());
  }
  ASSERT_GE(clip.size(), 6u);
  FramePyramid frame;
  frame.allocate(scene.camera, scene.depth_factor, DepthRange{0.3, 10.0});
  for (int i = 0; i < 4; ++i) {
    render_into(scene, testing::SyntheticScene::pose_at(0.5 * i), &frame);
    room.emplace_back();
    room.back().allocate(scene.camera);
    capture_view(frame, &room.back());
  }
  ViewAligner aligner;
  aligner.allocate(clip_params.camera, clip_params.sensor.depth_factor,
                   clip_params.sensor.depth_range, tracking_options(clip_params));
  const HealthLimits limits = health_limits(clip_params);
  const SE3 guesses[2] = {SE3(), SE3(so3_exp(Vector3d(0, 0.1, 0.05)), Vector3d(0.1, 0.05, 0))};
  int checked = 0;
  for (const View& c : clip) {
    for (const View& r : room) {
      for (int side = 0; side < 2; ++side) {
        aligner.set(side, c);
        aligner.set(1 - side, r);
        EXPECT_FALSE(shows_same_place(aligner.align(guesses, 2, limits))) << "a wrong place passed";
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, static_cast<int>(2 * clip.size() * room.size()));
  int found = 0;
  for (size_t i = 1; i < clip.size(); ++i) {
    aligner.set(0, clip[0]);
    aligner.set(1, clip[i]);
    found += shows_same_place(aligner.align(guesses, 1, limits));
  }
  EXPECT_GE(found, static_cast<int>(clip.size()) / 2) << "the clip's views find each other";
}

// A lost frame is found among the places of the keyframes before it, by appearance or near the
// last valid pose, and put where the ground truth says it is.
TEST(Relocaliser, FindsALaterFrameOfTheClipAmongItsPlaces) {
  Params p;
  ASSERT_TRUE(read_params_file(testing::source_path("config/tum_fr1.conf").c_str(), &p).is_ok());
  FrontendFrames frames;
  ASSERT_TRUE(frames.open(testing::source_path("data/tum_fr1_xyz_clip").c_str(), p).is_ok());
  std::vector<StampedPose> gt;
  int bad = 0;
  ASSERT_TRUE(read_tum_trajectory(
                  testing::source_path("data/tum_fr1_xyz_clip/groundtruth.txt").c_str(), &gt, &bad)
                  .is_ok());
  // The ground truth nearest a frame (100 Hz: within 5 ms).
  auto truth_at = [&](int frame, SE3* T) {
    const double t = frames.timestamp_ns(frame) * 1e-9;
    const StampedPose* best = &gt[0];
    for (const StampedPose& g : gt) {
      if (std::fabs(g.stamp_s - t) < std::fabs(best->stamp_s - t)) best = &g;
    }
    *T = best->T_w_c;
    return std::fabs(best->stamp_s - t) < 0.02;
  };
  PlaceStore store;
  store.allocate(16, p.loop.features, shipped_vocabulary().words(), p.camera);
  PlaceRecognizer recognizer;
  recognizer.allocate(p);
  // The first frame is the world's origin, as the tracker's first keyframe is.
  SE3 T_gt_world;
  ASSERT_TRUE(truth_at(0, &T_gt_world));
  for (int i = 0; i < 30; i += 6) {
    ASSERT_TRUE(frames.load(i));
    SE3 T_gt_c;
    ASSERT_TRUE(truth_at(i, &T_gt_c));
    recognizer.describe(frames.frame().gray(0), frames.frame().inverse_depth(0),
                        frames.frame().intrinsics(0), shipped_vocabulary());
    PlaceRecord* r = store.begin_insert();
    r->keyframe_id = static_cast<uint32_t>(i);
    r->T_w_k = T_gt_world.inverse() * T_gt_c;
    for (const Feature& feature : recognizer.features())
      ASSERT_TRUE(r->features.push_back(feature));
    for (const BowEntry& e : recognizer.bow()) ASSERT_TRUE(r->bow.push_back(e));
    capture_view(frames.frame(), &r->view);
    store.commit();
  }
  Relocaliser relocaliser;
  relocaliser.allocate(p);
  ASSERT_TRUE(frames.load(45));
  SE3 T_gt_45;
  ASSERT_TRUE(truth_at(45, &T_gt_45));
  const SE3 T_w_45 = T_gt_world.inverse() * T_gt_45;
  for (const bool with_last_pose : {true, false}) {
    const SE3 last = T_w_45 * SE3(so3_exp(Vector3d(0, 3 * kDeg, 0)), Vector3d(0.05, 0, 0));
    const Relocalisation r = relocaliser.find(frames.frame(), with_last_pose ? &last : nullptr,
                                              &store, shipped_vocabulary());
    ASSERT_TRUE(r.found) << (with_last_pose ? "near the last pose" : "by appearance alone");
    const SE3 error = T_w_45.inverse() * r.T_w_c();
    EXPECT_LT(error.translation().norm(), 0.03);
    EXPECT_LT(so3_log(error.quaternion()).norm(), 2 * kDeg);
  }
}

}  // namespace
}  // namespace rgbdtam

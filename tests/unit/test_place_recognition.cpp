// Place recognition's pieces: features, vocabulary, inverted index, rigid alignment, pose graph.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "measures.hpp"
#include "rgbdtam/core/features.hpp"
#include "rgbdtam/core/place_database.hpp"
#include "rgbdtam/core/pose_graph.hpp"
#include "rgbdtam/core/pyramid.hpp"
#include "rgbdtam/core/rigid_alignment.hpp"
#include "rgbdtam/core/vocabulary.hpp"
#include "synthetic_scene.hpp"

namespace rgbdtam {
namespace {

using testing::expect_close;
using testing::kDeg;

// A rendered view of the synthetic room as the tracker's frontend would hold it.
struct FeatureView {
  FramePyramid frame;
  FixedVector<Feature> features;
};

void render_view(const SE3& T_w_c, FeatureView* v, int max_features = 400) {
  static const testing::SyntheticScene scene;
  const testing::SyntheticFrame f = scene.render(T_w_c);
  v->frame.allocate(scene.camera, scene.depth_factor, DepthRange{0.3, 10.0});
  ImageU16 depth;
  depth.allocate(scene.camera.width_px, scene.camera.height_px);
  for (int i = 0; i < depth.size(); ++i) {
    depth.data()[i] = f.depth[static_cast<size_t>(i)];
    v->frame.gray(0).data()[i] = f.gray[static_cast<size_t>(i)] / 255.f;
  }
  v->frame.build_inverse_depth(depth);
  FeatureExtractor extractor;
  FeatureOptions opt;
  opt.max_features = max_features;
  extractor.allocate(scene.camera.width_px, scene.camera.height_px, opt);
  v->features.reserve_once(max_features);
  extractor.extract(v->frame.gray(0), v->frame.inverse_depth(0), v->frame.intrinsics(0),
                    &v->features);
}

SE3 start_pose() { return testing::SyntheticScene::pose_at(0.0); }

// T_b_a from a's view to b's, estimated by matching their features.
RigidRansacResult align(const FeatureView& a, const FeatureView& b, int* matches) {
  std::vector<PointPair> pairs(static_cast<size_t>(a.features.size()));
  *matches = match_features(a.features, b.features, pairs.data(), a.features.size());
  std::vector<uint8_t> inlier(pairs.size());
  RigidRansacOptions opt;
  return rigid_ransac(pairs.data(), *matches, opt, inlier.data());
}

TEST(Features, CornersWithDepthSpreadOverTheView) {
  FeatureView v;
  render_view(start_pose(), &v);
  ASSERT_GE(v.features.size(), 200);
  int cells[4] = {};  // image quadrants
  for (const Feature& f : v.features) {
    EXPECT_GT(f.z_m, 0.3f);
    ++cells[(f.u_px < 320 ? 0 : 1) + (f.v_px < 240 ? 0 : 2)];
  }
  for (const int c : cells) EXPECT_GE(c, 20) << "a quadrant without features";
}

TEST(Features, TheSameViewGivesTheSameFeatures) {
  FeatureView a, b;
  render_view(start_pose(), &a);
  render_view(start_pose(), &b);
  ASSERT_EQ(a.features.size(), b.features.size());
  for (int i = 0; i < a.features.size(); ++i) {
    EXPECT_EQ(hamming(a.features[i].descriptor, b.features[i].descriptor), 0);
  }
}

// Views from the start pose and from it moved by `motion`: their matches, aligned by RANSAC,
// give back the motion.
void expect_views_align(const SE3& motion, int min_inliers) {
  const SE3 T_w_a = start_pose();
  const SE3 T_w_b = T_w_a * motion;
  FeatureView a, b;
  render_view(T_w_a, &a);
  render_view(T_w_b, &b);
  int matches = 0;
  const RigidRansacResult r = align(a, b, &matches);
  EXPECT_GE(r.inliers, min_inliers) << matches << " matches";
  expect_close(r.T_b_a, T_w_b.inverse() * T_w_a, 0.01, 0.5 * kDeg);
}

TEST(Features, MatchesRecoverTheMotionBetweenTwoViews) {
  expect_views_align(SE3(so3_exp(Vector3d(0.02, -0.05, 0.01)), Vector3d(0.08, 0.03, -0.05)), 60);
}

TEST(Features, AThirtyDegreeRollStillMatches) {
  // The descriptor turns with the corner's orientation.
  expect_views_align(SE3(so3_exp(Vector3d(0, 0, 30 * kDeg)), Vector3d::Zero()), 40);
}

// Rendered once a process: the HIL runner runs a binary's tests in one, where rendering them
// for each test took most of the vocabulary tests' 30 s under qemu.
const std::vector<std::vector<Descriptor>>& training_images() {
  static const std::vector<std::vector<Descriptor>> images = [] {
    std::vector<std::vector<Descriptor>> rendered;
    for (int i = 0; i < 4; ++i) {
      FeatureView v;
      render_view(start_pose() * SE3(so3_exp(Vector3d(0, 0.1 * i, 0)), Vector3d(0.1 * i, 0, 0)),
                  &v);
      std::vector<Descriptor> d;
      for (const Feature& f : v.features) d.push_back(f.descriptor);
      rendered.push_back(d);
    }
    return rendered;
  }();
  return images;
}

std::vector<uint8_t> bytes_of(const Vocabulary& v) {
  std::vector<uint8_t> b(v.serialized_size());
  v.serialize(b.data());
  return b;
}

uint32_t fnv1a(const uint8_t* data, size_t size) {
  uint32_t h = 2166136261u;
  for (size_t i = 0; i < size; ++i) h = (h ^ data[i]) * 16777619u;
  return h;
}

TEST(Vocabulary, TrainingIsDeterministicAndTheFileRoundTrips) {
  const auto& images = training_images();
  const std::vector<uint8_t> first = bytes_of(Vocabulary::train(images, 5, 3));
  const std::vector<uint8_t> second = bytes_of(Vocabulary::train(images, 5, 3));
  EXPECT_EQ(first, second);
  Vocabulary parsed;
  ASSERT_TRUE(Vocabulary::parse(first.data(), first.size(), &parsed).is_ok());
  const Vocabulary trained = Vocabulary::train(images, 5, 3);
  EXPECT_EQ(parsed.words(), trained.words());
  EXPECT_GT(parsed.words(), 50);
  for (const Descriptor& d : images[1]) EXPECT_EQ(parsed.word_of(d), trained.word_of(d));
}

TEST(Vocabulary, DamagedFilesAreRefusedWithTheReason) {
  std::vector<uint8_t> good = bytes_of(Vocabulary::train(training_images(), 5, 3));
  Vocabulary v;
  auto refused = [&](std::vector<uint8_t> bytes, const char* why) {
    const Status s = Vocabulary::parse(bytes.data(), bytes.size(), &v);
    EXPECT_FALSE(s.is_ok()) << why;
    EXPECT_NE(std::strstr(s.message(), why), nullptr) << s.message();
  };
  refused(std::vector<uint8_t>(good.begin(), good.begin() + 10), "not a vocabulary file");
  refused(std::vector<uint8_t>(good.begin(), good.end() - 8), "should be");
  std::vector<uint8_t> flipped = good;
  flipped[100] ^= 0x10;
  refused(flipped, "checksum");
  // A node whose child points back at the root, with a valid checksum: the descent would loop.
  std::vector<uint8_t> cyclic = good;
  const size_t root_first_child = 24 + 32;
  const int32_t zero = 0;
  std::memcpy(&cyclic[root_first_child], &zero, 4);
  const uint32_t sum = fnv1a(cyclic.data(), cyclic.size() - 4);
  std::memcpy(&cyclic[cyclic.size() - 4], &sum, 4);
  refused(cyclic, "inconsistent");
  EXPECT_EQ(v.words(), 0) << "a refused file leaves the vocabulary empty";
}

TEST(Vocabulary, BagOfWordsIsNormalisedAndScoresItselfOne) {
  const auto& images = training_images();
  const Vocabulary voc = Vocabulary::train(images, 5, 3);
  FeatureView v;
  render_view(start_pose(), &v);
  BowVector bow;
  bow.reserve_once(v.features.size());
  voc.transform(v.features, &bow);
  ASSERT_FALSE(bow.empty());
  double sum = 0;
  for (int i = 0; i < bow.size(); ++i) {
    sum += bow[i].weight;
    if (i > 0) {
      EXPECT_LT(bow[i - 1].word, bow[i].word);
    }
  }
  EXPECT_NEAR(sum, 1.0, 1e-5);
  EXPECT_NEAR(bow_score(bow, bow), 1.0, 1e-5);
}

BowVector make_bow(std::initializer_list<BowEntry> entries) {
  BowVector v;
  v.reserve_once(8);
  for (const BowEntry& e : entries) EXPECT_TRUE(v.push_back(e));
  return v;
}

TEST(PlaceDatabase, RanksSharedWordsAndForgetsRemovedPlaces) {
  PlaceDatabase db;
  db.allocate(4, 10, 8);
  const BowVector a = make_bow({{1, 0.5f}, {2, 0.5f}});
  const BowVector b = make_bow({{2, 0.25f}, {3, 0.75f}});
  const BowVector c = make_bow({{7, 1.0f}});
  db.add(0, a);
  db.add(1, b);
  db.add(2, c);
  PlaceMatch m[4];
  int n = db.query(a, nullptr, nullptr, m, 4);
  ASSERT_EQ(n, 2) << "c shares no word with a";
  EXPECT_EQ(m[0].slot, 0);
  EXPECT_NEAR(m[0].score, 1.0, 1e-6);
  EXPECT_EQ(m[1].slot, 1);
  EXPECT_NEAR(m[1].score, 0.25, 1e-6);
  EXPECT_NEAR(m[1].score, bow_score(a, b), 1e-6);
  db.remove(0);
  n = db.query(a, nullptr, nullptr, m, 4);
  ASSERT_EQ(n, 1);
  EXPECT_EQ(m[0].slot, 1);
  // A slot given a new place holds only the new one.
  db.add(1, c);
  EXPECT_EQ(db.query(a, nullptr, nullptr, m, 4), 0);
  const auto only_slot_two = [](const void*, int slot) { return slot == 2; };
  db.add(3, c);
  n = db.query(c, only_slot_two, nullptr, m, 4);
  ASSERT_EQ(n, 1);
  EXPECT_EQ(m[0].slot, 2);
}

std::vector<PointPair> pairs_under(const SE3& T_b_a, int n) {
  std::vector<PointPair> pairs;
  for (int i = 0; i < n; ++i) {
    const Vector3d a(std::sin(1.3 * i), std::cos(0.7 * i), 1.0 + 0.05 * i);
    pairs.push_back({a, T_b_a * a});
  }
  return pairs;
}

TEST(RigidAlignment, HornRecoversAnExactMotion) {
  const SE3 T(so3_exp(Vector3d(0.3, -0.2, 0.5)), Vector3d(0.4, -1.0, 0.2));
  const auto pairs = pairs_under(T, 10);
  SE3 estimate;
  ASSERT_TRUE(horn_alignment(pairs.data(), 10, nullptr, &estimate));
  expect_close(estimate, T, 1e-9, 1e-9);
  // Collinear points leave the turn about their line free.
  std::vector<PointPair> line;
  for (int i = 0; i < 5; ++i) line.push_back({Vector3d(i, 0, 1), T * Vector3d(i, 0, 1)});
  EXPECT_FALSE(horn_alignment(line.data(), 5, nullptr, &estimate));
}

TEST(RigidAlignment, RansacIgnoresHalfTheMatchesBeingWrong) {
  const SE3 T(so3_exp(Vector3d(0.1, 0.2, -0.1)), Vector3d(0.1, 0.0, -0.3));
  auto pairs = pairs_under(T, 60);
  for (int i = 0; i < 60; i += 2)
    pairs[static_cast<size_t>(i)].b += Vector3d(0.5, -0.3, 0.4 + 0.01 * i);
  std::vector<uint8_t> inlier(60);
  const RigidRansacResult r = rigid_ransac(pairs.data(), 60, RigidRansacOptions(), inlier.data());
  EXPECT_EQ(r.inliers, 30);
  expect_close(r.T_b_a, T, 1e-6, 1e-6);
  for (int i = 0; i < 60; ++i) EXPECT_EQ(inlier[static_cast<size_t>(i)], i % 2) << i;
}

// A square loop of 24 poses whose odometry turns 0.5 degrees too far each step.
struct DriftingLoop {
  std::vector<SE3> truth, drifted;
  std::vector<SE3> odometry;  // measured T_i_(i+1)
};

DriftingLoop drifting_loop() {
  DriftingLoop d;
  const int n = 24;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    d.truth.push_back(SE3(so3_exp(Vector3d(0, a, 0)), Vector3d(std::cos(a), 0, std::sin(a))));
  }
  d.drifted.push_back(d.truth[0]);
  for (int i = 0; i + 1 < n; ++i) {
    const SE3 bias(so3_exp(Vector3d(0, 0.5 * kDeg, 0)), Vector3d(0.005, 0, 0));
    d.odometry.push_back(d.truth[static_cast<size_t>(i)].inverse() *
                         d.truth[static_cast<size_t>(i) + 1] * bias);
    d.drifted.push_back(d.drifted.back() * d.odometry.back());
  }
  return d;
}

double worst_error_m(const PoseGraph& g, const std::vector<SE3>& truth) {
  double worst = 0;
  for (int i = 0; i < g.nodes(); ++i) {
    worst = std::max(
        worst, (g.pose(i).translation() - truth[static_cast<size_t>(i)].translation()).norm());
  }
  return worst;
}

TEST(PoseGraph, ALoopEdgeTakesAwayMostOfTheDrift) {
  const DriftingLoop d = drifting_loop();
  PoseGraph g;
  g.allocate(32, 64);
  for (const SE3& T : d.drifted) g.add_node(T);
  const Matrix6d odometry_information = 1e4 * Matrix6d::Identity();
  for (int i = 0; i + 1 < g.nodes(); ++i) {
    ASSERT_TRUE(g.add_edge(i, i + 1, d.odometry[static_cast<size_t>(i)], odometry_information));
  }
  const double before = worst_error_m(g, d.truth);
  // The loop: the last pose seen again from the first, measured exactly.
  const int last = g.nodes() - 1;
  ASSERT_TRUE(g.add_edge(0, last, d.truth[0].inverse() * d.truth[static_cast<size_t>(last)],
                         1e6 * Matrix6d::Identity()));
  const PoseGraphStats s = g.optimize(10);
  const double after = worst_error_m(g, d.truth);
  std::printf("drift %.3f m before, %.3f m after; cost %.1f -> %.3f in %d steps, %d CG\n", before,
              after, s.initial_cost, s.final_cost, s.iterations, s.cg_iterations);
  EXPECT_GT(before, 0.15);
  EXPECT_LT(after, 0.25 * before);
  EXPECT_LT(s.final_cost, 0.01 * s.initial_cost);
  expect_close(g.pose(0), d.truth[0], 1e-12, 1e-12);  // the gauge stays put
}

TEST(PoseGraph, AConsistentGraphDoesNotMove) {
  const DriftingLoop d = drifting_loop();
  PoseGraph g;
  g.allocate(32, 64);
  for (const SE3& T : d.truth) g.add_node(T);
  for (int i = 0; i + 1 < g.nodes(); ++i) {
    ASSERT_TRUE(g.add_edge(
        i, i + 1, d.truth[static_cast<size_t>(i)].inverse() * d.truth[static_cast<size_t>(i) + 1],
        Matrix6d::Identity()));
  }
  g.optimize(5);
  for (int i = 0; i < g.nodes(); ++i)
    expect_close(g.pose(i), d.truth[static_cast<size_t>(i)], 1e-9, 1e-9);
}

TEST(PoseGraph, AFullGraphRefusesMoreAndSaysSo) {
  PoseGraph g;
  g.allocate(2, 1);
  EXPECT_EQ(g.add_node(SE3()), 0);
  EXPECT_EQ(g.add_node(SE3()), 1);
  EXPECT_EQ(g.add_node(SE3()), -1);
  EXPECT_TRUE(g.add_edge(0, 1, SE3(), Matrix6d::Identity()));
  EXPECT_FALSE(g.add_edge(1, 0, SE3(), Matrix6d::Identity()));
}

}  // namespace
}  // namespace rgbdtam

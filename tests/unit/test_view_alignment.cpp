// Direct alignment of coarse views (loop closure's and relocalisation's verification), and the
// information algebra of the keyframe graph's edges.
#include <gtest/gtest.h>

#include <cmath>

#include "measures.hpp"
#include "rgbdtam/core/pose_graph.hpp"
#include "rgbdtam/core/view_alignment.hpp"
#include "synthetic_scene.hpp"

namespace rgbdtam {
namespace {

using testing::expect_close;
using testing::kDeg;

// Views of a synthetic scene, as a tracker's frame pyramid gives them.
class Views {
 public:
  explicit Views(const testing::SyntheticScene& scene) : scene_(scene) {
    frame_.allocate(scene.camera, scene.depth_factor, DepthRange{0.3, 10.0});
    depth_.allocate(scene.camera.width_px, scene.camera.height_px);
  }
  View at(const SE3& T_w_c) {
    const testing::SyntheticFrame f = scene_.render(T_w_c);
    for (int i = 0; i < depth_.size(); ++i) {
      depth_.data()[i] = f.depth[static_cast<size_t>(i)];
      frame_.gray(0).data()[i] = f.gray[static_cast<size_t>(i)] / 255.f;
    }
    frame_.build_gray();
    frame_.build_inverse_depth(depth_);
    View v;
    v.allocate(scene_.camera);
    capture_view(frame_, &v);
    return v;
  }
  const FramePyramid& frame() const { return frame_; }

 private:
  testing::SyntheticScene scene_;
  FramePyramid frame_;
  ImageU16 depth_;
};

struct Aligner {
  explicit Aligner(const testing::SyntheticScene& scene) {
    TrackerOptions tracking;
    tracking.inverse_depth_sigma = 0.1 / (580.0 * 0.075);  // the synthetic sensor's
    aligner.allocate(scene.camera, scene.depth_factor, DepthRange{0.3, 10.0}, tracking);
  }
  ViewAlignment align(const View& a, const View& b, const SE3& guess) {
    aligner.set(0, a);
    aligner.set(1, b);
    return aligner.align(&guess, 1, HealthLimits());
  }
  ViewAligner aligner;
};

TEST(View, IsTheFramesViewLevelQuantised) {
  const testing::SyntheticScene scene;
  Views views(scene);
  const View v = views.at(testing::SyntheticScene::pose_at(0.0));
  ASSERT_EQ(View::level(scene.camera), 2) << "160x120 of 640x480";
  ASSERT_EQ(View::level(testing::SyntheticScene::half_resolution().camera), 1)
      << "80x60 is too small";
  ASSERT_EQ(v.gray.width(), scene.camera.width_px >> 2);
  const ImageF& gray = views.frame().gray(2);
  const ImageF& inverse_depth = views.frame().inverse_depth(2);
  int with_depth = 0;
  for (int i = 0; i < gray.size(); ++i) {
    EXPECT_NEAR(v.gray.data()[i] / 255.0, gray.data()[i], 0.5 / 255.0 + 1e-6);
    const double stored = v.inverse_depth.data()[i] * static_cast<double>(kViewInverseDepthStep);
    EXPECT_NEAR(stored, inverse_depth.data()[i], 0.5 * kViewInverseDepthStep + 1e-6);
    with_depth += v.inverse_depth.data()[i] > 0;
  }
  EXPECT_GT(with_depth, gray.size() / 2);
  EXPECT_EQ(View::bytes(scene.camera), static_cast<size_t>(v.gray.size()) * 3);
}

TEST(ViewAlignment, MeasuresARevisitFromTheMapsDriftedGuessBothWays) {
  const testing::SyntheticScene scene;
  Views views(scene);
  Aligner aligner(scene);
  const SE3 T_w_a = testing::SyntheticScene::pose_at(0.0);
  const SE3 T_a_b(so3_exp(Vector3d(0.01, -0.04, 0.02)), Vector3d(0.08, -0.03, 0.05));
  const View a = views.at(T_w_a), b = views.at(T_w_a * T_a_b);
  // The map's guess after drift: 3 cm and 2 degrees off.
  const SE3 guess = T_a_b * SE3(so3_exp(Vector3d(0, 2 * kDeg, 0)), Vector3d(0.03, 0, 0));
  const ViewAlignment r = aligner.align(a, b, guess);
  EXPECT_EQ(r.forward_failed, 0u);
  EXPECT_EQ(r.backward_failed, 0u);
  EXPECT_TRUE(shows_same_place(r));
  EXPECT_TRUE(measures_pose(r));
  expect_close(r.T_a_b, T_a_b, 0.01, 0.5 * kDeg);
  EXPECT_LT(r.disagreement_m, 0.01);
}

TEST(ViewAlignment, FindsThePlaceFromItsOwnPoseWhenTheMapHasNoGuess) {
  // A relocalised frame or a place after a restart: the first guess is the place's own pose,
  // 12 cm and 6 degrees away; the turned copies of the wider basin reach it.
  const testing::SyntheticScene scene;
  Views views(scene);
  Aligner aligner(scene);
  const SE3 T_w_a = testing::SyntheticScene::pose_at(0.0);
  const SE3 T_a_b(so3_exp(Vector3d(0.0, 6 * kDeg, 0.0)), Vector3d(0.1, 0.05, 0.04));
  const ViewAlignment r = aligner.align(views.at(T_w_a), views.at(T_w_a * T_a_b), SE3());
  EXPECT_TRUE(shows_same_place(r));
  expect_close(r.T_a_b, T_a_b, 0.01, 0.5 * kDeg);
}

TEST(ViewAlignment, AnotherSceneIsNeverTheSamePlace) {
  // The textured room against the plain corridor and room, from every guess tried.
  const testing::SyntheticScene room;
  testing::SyntheticScene corridor, plain;
  corridor.layout = testing::SyntheticScene::Layout::kCorridor;
  plain.layout = testing::SyntheticScene::Layout::kPlainRoom;
  Views room_views(room), corridor_views(corridor), plain_views(plain);
  Aligner aligner(room);
  int tried = 0;
  for (int i = 0; i < 3; ++i) {
    const View a = room_views.at(testing::SyntheticScene::pose_at(0.5 * i));
    for (Views* other : {&corridor_views, &plain_views}) {
      const View b = other == &corridor_views ? other->at(corridor.camera_at(0.7 * i))
                                              : other->at(plain.camera_at(0.7 * i));
      for (const SE3& guess : {SE3(), SE3(so3_exp(Vector3d(0, 0.2, 0)), Vector3d(0.2, 0, 0))}) {
        EXPECT_FALSE(shows_same_place(aligner.align(a, b, guess))) << "view " << i;
        EXPECT_FALSE(shows_same_place(aligner.align(b, a, guess))) << "view " << i;
        tried += 2;
      }
    }
  }
  EXPECT_EQ(tried, 24);
}

// The graph's information of T_a_b = T_a_f T_b_f^-1, to first order: with right perturbations
// xa, xb of the two measurements, the result moves by Ad(T_b_f) (xa - xb).
TEST(EdgeInformation, ThroughAFrameFollowsTheAdjoint) {
  const SE3 T_a_f(so3_exp(Vector3d(0.2, -0.1, 0.3)), Vector3d(0.4, 0.1, -0.2));
  const SE3 T_b_f(so3_exp(Vector3d(-0.3, 0.2, 0.1)), Vector3d(-0.1, 0.5, 0.3));
  Vector6d xa, xb;
  xa << 1e-5, -2e-5, 3e-5, 2e-5, 1e-5, -1e-5;
  xb << -2e-5, 1e-5, 1e-5, -1e-5, 3e-5, 2e-5;
  const SE3 T_a_b = T_a_f * T_b_f.inverse();
  const SE3 moved = (T_a_f * SE3::exp(xa)) * (T_b_f * SE3::exp(xb)).inverse();
  const Vector6d measured = (T_a_b.inverse() * moved).log();
  const Vector6d predicted = adjoint(T_b_f) * (xa - xb);
  EXPECT_LT((measured - predicted).norm(), 1e-8);
  // Two equal, independent measurements through the identity: half the information.
  const Matrix6d I = 1e4 * Matrix6d::Identity();
  EXPECT_LT((information_through(I, I, SE3()) - 0.5 * I).norm(), 1e-3);
  // The tracker's convention T_c_k exp(-delta) to the graph's T_k_c exp(xi): equal costs.
  Matrix6d tracker = Matrix6d::Identity();
  tracker(0, 0) = 4.0;
  tracker(4, 4) = 9.0;
  const Matrix6d graph = graph_information(tracker, T_a_f);
  // T_k_c exp(xi) = exp(delta) T_k_c: the inverse T_c_k gets T_c_k exp(-delta).
  const Vector6d xi = xa * 1e4;
  const SE3 T_c_k_moved = (T_a_f * SE3::exp(xi)).inverse();
  const Vector6d delta = -(T_a_f * T_c_k_moved).log();
  EXPECT_NEAR(xi.dot(graph * xi), delta.dot(tracker * delta), 1e-6 * xi.dot(graph * xi));
}

TEST(PoseGraphInformation, AJumpIsAddedToEveryAxisOfTheCovariance) {
  // Standard deviations of 1 mm and 1 mrad, and a jump of 1.6 cm and 0.01 rad.
  Matrix6d information = Matrix6d::Identity() * 1e6;
  information(1, 2) = information(2, 1) = 2e5;  // correlated axes keep their correlation
  const Matrix6d widened = information_with_jump(information, 0.016, 0.01);
  const Matrix6d expected_cov =
      information.inverse() + (Vector6d() << 2.56e-4, 2.56e-4, 2.56e-4, 1e-4, 1e-4, 1e-4)
                                  .finished()
                                  .asDiagonal()
                                  .toDenseMatrix();
  EXPECT_LT((widened.inverse() - expected_cov).norm(), 1e-9);
  EXPECT_LT((information_with_jump(information, 0.0, 0.0) - information).norm(), 1e-3);
}

}  // namespace
}  // namespace rgbdtam

// Keyframe-side Jacobians of both residuals against central differences of the residual
// itself, at the identity pose where the inverse-compositional Jacobian is exact.
#include <gtest/gtest.h>

#include <cmath>

#include "rgbdtam/core/tracker.hpp"
#include "synthetic_scene.hpp"

namespace rgbdtam {
namespace {

struct Fixture {
  testing::SyntheticScene scene;
  FramePyramid pyramid;
  KeyframeBuilder builder;
  Keyframe kf;
  explicit Fixture(const char* residuals) {
    TrackerOptions opt;
    EXPECT_TRUE(ResidualConfig::parse(residuals, &opt.residuals));
    // Depth gradients change little on smooth planes; the box edge is excluded by the builder.
    const testing::SyntheticFrame f = scene.render(SE3());
    pyramid.allocate(scene.camera, scene.depth_factor, DepthRange{0.1, 10.0});
    Undistorter u;
    u.init(scene.camera, RadTanDistortion());
    u.undistort_gray(f.gray.data(), &pyramid.gray(0));
    pyramid.build_gray();
    ImageU16 depth;
    depth.allocate(scene.camera.width_px, scene.camera.height_px);
    for (int i = 0; i < depth.size(); ++i) depth.data()[i] = f.depth[static_cast<size_t>(i)];
    pyramid.build_inverse_depth(depth);
    builder.allocate(scene.camera, opt);
    builder.allocate_keyframe(&kf);
    builder.build(pyramid, 0, 0, SE3(), &kf);
  }
};

// Residual of one point at T_c_k = exp(-delta), with the tracker's conventions.
bool residual(const ImageF& img, const PinholeIntrinsics& k, const TrackPoint& p,
              const Vector6d& delta, bool geometric, double* r) {
  const SE3 T = SE3::exp(-delta);
  const Vector3d q = T * Vector3d(p.x, p.y, p.z);
  const double u = k.fx_px * q.x() / q.z() + k.cx_px;
  const double v = k.fy_px * q.y() / q.z() + k.cy_px;
  if (!img.contains(static_cast<float>(u), static_cast<float>(v), 2.f)) return false;
  const double s = sample_bilinear(img, static_cast<float>(u), static_cast<float>(v));
  *r = geometric ? 1.0 / q.z() - s : s - p.ref;
  return true;
}

void check_jacobians(const Fixture& fx, bool geometric, int level) {
  const TrackPoints& pts = geometric ? fx.kf.geometric[level] : fx.kf.photometric(level);
  const ImageF& img = geometric ? fx.pyramid.inverse_depth(level) : fx.pyramid.gray(level);
  const PinholeIntrinsics& k = fx.pyramid.intrinsics(level);
  ASSERT_GT(pts.size(), 50);
  int checked = 0, agree = 0;
  // Bilinear interpolation has kinks at pixel borders; a small step keeps both sides inside
  // one cell for most points, and the median point must agree closely.
  const double h = 1e-6;
  for (int i = 0; i < pts.size(); i += std::max(1, pts.size() / 200)) {
    const TrackPoint& p = pts[i];
    double num[6], scale = 0;
    bool ok = true;
    for (int j = 0; j < 6 && ok; ++j) {
      Vector6d d = Vector6d::Zero();
      d[j] = h;
      double rp = 0, rm = 0;
      ok = residual(img, k, p, d, geometric, &rp) && residual(img, k, p, -d, geometric, &rm);
      num[j] = (rp - rm) / (2 * h);
      scale = std::max(scale, std::fabs(num[j]));
    }
    if (!ok || scale == 0) continue;
    ++checked;
    double worst = 0;
    for (int j = 0; j < 6; ++j) worst = std::max(worst, std::fabs(num[j] - p.J[j]) / scale);
    if (worst < 0.05) ++agree;
  }
  ASSERT_GT(checked, 20);
  EXPECT_GT(agree, checked * 9 / 10) << (geometric ? "geometric" : "photometric") << " level "
                                     << level << ": " << agree << " of " << checked;
}

TEST(Jacobians, PhotometricMatchesNumericAtEveryLevel) {
  Fixture f("PS");
  for (int l = 0; l < kPyramidLevels; ++l) check_jacobians(f, false, l);
}

TEST(Jacobians, InverseDepthMatchesNumericAtEveryLevel) {
  Fixture f("GIDD");
  for (int l = 0; l < kPyramidLevels; ++l) check_jacobians(f, true, l);
}

}  // namespace
}  // namespace rgbdtam

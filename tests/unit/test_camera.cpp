// Camera projection, distortion and undistortion round trips; pyramid intrinsics.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rgbdtam/core/camera.hpp"
#include "rgbdtam/core/pyramid.hpp"
#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {
namespace {

const RadTanDistortion kFr1{0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
const PinholeIntrinsics kFr1Intrinsics{517.3, 516.5, 318.6, 255.3, 640, 480};

TEST(Distortion, UndistortInvertsDistortAcrossTheImage) {
  for (double u = 0; u <= 640; u += 40) {
    for (double v = 0; v <= 480; v += 40) {
      const double x = (u - kFr1Intrinsics.cx_px) / kFr1Intrinsics.fx_px,
                   y = (v - kFr1Intrinsics.cy_px) / kFr1Intrinsics.fy_px;
      double xd, yd, xu, yu;
      kFr1.distort(x, y, &xd, &yd);
      kFr1.undistort(xd, yd, &xu, &yu);
      EXPECT_NEAR(xu, x, 1e-9);
      EXPECT_NEAR(yu, y, 1e-9);
    }
  }
}

TEST(Undistorter, MovesAnImpulseToWhereTheModelSays) {
  // A bright pixel in the raw image must appear at the undistorted position of that pixel.
  Undistorter und;
  und.init(kFr1Intrinsics, kFr1);
  ASSERT_FALSE(und.is_identity());
  const int rx = 80, ry = 60;  // far from the centre, where distortion is strong
  std::vector<uint8_t> raw(640 * 480, 0);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) raw[(ry + dy) * 640 + rx + dx] = 255;
  ImageF out;
  out.allocate(640, 480);
  und.undistort_gray(raw.data(), &out);
  double xu, yu;
  kFr1.undistort((rx - kFr1Intrinsics.cx_px) / kFr1Intrinsics.fx_px,
                 (ry - kFr1Intrinsics.cy_px) / kFr1Intrinsics.fy_px, &xu, &yu);
  const double eu = kFr1Intrinsics.fx_px * xu + kFr1Intrinsics.cx_px,
               ev = kFr1Intrinsics.fy_px * yu + kFr1Intrinsics.cy_px;
  double sum = 0, su = 0, sv = 0;
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 640; ++x) {
      sum += out.at(x, y);
      su += x * out.at(x, y);
      sv += y * out.at(x, y);
    }
  ASSERT_GT(sum, 0);
  EXPECT_NEAR(su / sum, eu, 0.5);
  EXPECT_NEAR(sv / sum, ev, 0.5);
  EXPECT_GT(std::hypot(eu - rx, ev - ry), 5.0) << "the test point should move noticeably";
}

TEST(Undistorter, IdentityWithoutDistortionAndNearestForDepth) {
  Undistorter und;
  und.init(kFr1Intrinsics, RadTanDistortion());
  EXPECT_TRUE(und.is_identity());
  std::vector<uint16_t> depth(640 * 480);
  for (size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<uint16_t>(i % 5000);
  std::vector<float> as_is(1 << 16);  // a table that keeps the raw value
  for (size_t v = 0; v < as_is.size(); ++v) as_is[v] = static_cast<float>(v);
  ImageF out;
  out.allocate(640, 480);
  und.undistort_depth(depth.data(), as_is.data(), &out);
  for (size_t i = 0; i < depth.size(); i += 997) EXPECT_EQ(out.data()[i], depth[i]);
  // With distortion, every output depth is one of the input values (no interpolation).
  Undistorter d;
  d.init(kFr1Intrinsics, kFr1);
  std::vector<uint16_t> two(640 * 480);
  for (size_t i = 0; i < two.size(); ++i) two[i] = (i / 640) % 2 ? 1000 : 3000;
  d.undistort_depth(two.data(), as_is.data(), &out);
  for (int i = 0; i < out.size(); ++i) {
    const float v = out.data()[i];
    EXPECT_TRUE(v == 0.f || v == 1000.f || v == 3000.f) << v;
  }
}

TEST(Pyramid, IntrinsicsFollowPixelCentres) {
  // A 3-D point projects to level l at (u0 - 0.5(2^l - 1)) / 2^l, the 2x2-average convention.
  FramePyramid p;
  p.allocate(kFr1Intrinsics, 5000.0, DepthRange());
  const Vector3d X(0.2, -0.1, 1.5);
  const double u0 = kFr1Intrinsics.fx_px * X.x() / X.z() + kFr1Intrinsics.cx_px;
  for (int l = 0; l < kPyramidLevels; ++l) {
    const PinholeIntrinsics& k = p.intrinsics(l);
    const double s = std::pow(2.0, l);
    EXPECT_EQ(k.width_px, 640 >> l);
    EXPECT_NEAR(k.fx_px * X.x() / X.z() + k.cx_px, (u0 - 0.5 * (s - 1)) / s, 1e-9);
  }
  EXPECT_EQ(p.intrinsics(3).width_px, 80);
  EXPECT_EQ(p.intrinsics(3).height_px, 60);
}

}  // namespace
}  // namespace rgbdtam

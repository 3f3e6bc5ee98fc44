// Pyramid construction, gradients and the Canny detector.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "rgbdtam/core/canny.hpp"
#include "rgbdtam/core/pyramid.hpp"

namespace rgbdtam {
namespace {

const PinholeIntrinsics kImageCamera{500, 500, 319.5, 239.5, 640, 480};

TEST(Pyramid, GrayLevelsAreTwoByTwoAverages) {
  FramePyramid p;
  p.allocate(kImageCamera, 5000.0, DepthRange());
  ImageF& g = p.gray(0);
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 640; ++x) g.at(x, y) = static_cast<float>((x * 7 + y * 13) % 256) / 255.f;
  p.build_gray();
  for (int l = 1; l < kPyramidLevels; ++l) {
    const ImageF& fine = p.gray(l - 1);
    const ImageF& coarse = p.gray(l);
    for (int y = 0; y < coarse.height(); y += 7)
      for (int x = 0; x < coarse.width(); x += 5) {
        const float avg = 0.25f * (fine.at(2 * x, 2 * y) + fine.at(2 * x + 1, 2 * y) +
                                   fine.at(2 * x, 2 * y + 1) + fine.at(2 * x + 1, 2 * y + 1));
        EXPECT_FLOAT_EQ(coarse.at(x, y), avg);
      }
  }
}

TEST(Pyramid, InverseDepthRangeAndEdges) {
  FramePyramid p;
  p.allocate(kImageCamera, 5000.0, DepthRange{0.3, 5.0});
  ImageU16 depth;
  depth.allocate(640, 480);
  // Left half at 1 m, right half at 2 m, a strip of no measurement, a strip too far.
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 640; ++x) {
      uint16_t d = x < 320 ? 5000 : 10000;
      if (y < 16) d = 0;
      if (y >= 464) d = 60000;  // 12 m, beyond depth.max
      depth.at(x, y) = d;
    }
  p.build_inverse_depth(depth);
  ASSERT_TRUE(p.has_depth());
  EXPECT_FLOAT_EQ(p.inverse_depth(0).at(10, 100), 1.0f);
  EXPECT_FLOAT_EQ(p.inverse_depth(0).at(600, 100), 0.5f);
  EXPECT_EQ(p.inverse_depth(0).at(10, 5), 0.f);
  EXPECT_EQ(p.inverse_depth(0).at(10, 470), 0.f);
  // Coarse levels average within a surface and never across the 1 m / 2 m edge.
  for (int l = 1; l < kPyramidLevels; ++l) {
    const ImageF& d = p.inverse_depth(l);
    for (int y = 0; y < d.height(); ++y)
      for (int x = 0; x < d.width(); ++x) {
        const float v = d.at(x, y);
        EXPECT_TRUE(v == 0.f || v == 1.0f || v == 0.5f) << "level " << l << " value " << v;
      }
  }
  p.clear_depth();
  EXPECT_FALSE(p.has_depth());
}

// Every coarse inverse depth against the rule written plainly: a 2x2 block with at least two
// valid values whose smallest is at least 0.9 of its largest is their mean, else none. Depths
// within 20 % of each other put many blocks on both sides of the 0.9.
TEST(Pyramid, InverseDepthBlocksFollowTheAgreementRule) {
  FramePyramid p;
  p.allocate(kImageCamera, 5000.0, DepthRange{0.3, 5.0});
  ImageU16 depth;
  depth.allocate(640, 480);
  uint32_t state = 7;
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 640; ++x) {
      state = state * 1664525u + 1013904223u;
      const uint32_t r = state >> 8;
      depth.at(x, y) = r % 10 < 2    ? 0
                       : r % 10 == 2 ? 60000
                                     : static_cast<uint16_t>(5000 + r % 1200);
    }
  p.build_inverse_depth(depth);
  int averaged = 0, refused = 0;
  for (int l = 1; l < kPyramidLevels; ++l) {
    const ImageF& fine = p.inverse_depth(l - 1);
    const ImageF& coarse = p.inverse_depth(l);
    for (int y = 0; y < coarse.height(); ++y)
      for (int x = 0; x < coarse.width(); ++x) {
        const float v[4] = {fine.at(2 * x, 2 * y), fine.at(2 * x + 1, 2 * y),
                            fine.at(2 * x, 2 * y + 1), fine.at(2 * x + 1, 2 * y + 1)};
        int n = 0;
        float lo = 1e30f, hi = 0.f, sum = 0.f;
        for (const float d : v) {
          sum += d;
          hi = std::max(hi, d);
          if (d > 0.f) {
            ++n;
            lo = std::min(lo, d);
          }
        }
        const bool agree = n >= 2 && lo >= 0.9f * hi;
        (agree ? averaged : refused) += 1;
        ASSERT_EQ(coarse.at(x, y), agree ? sum / n : 0.f)
            << "level " << l << " at " << x << ", " << y;
      }
  }
  EXPECT_GT(averaged, 1000);
  EXPECT_GT(refused, 1000);
}

TEST(Gradients, CentralDifferencesOfARamp) {
  ImageF img, gx, gy;
  img.allocate(64, 48);
  gx.allocate(64, 48);
  gy.allocate(64, 48);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) img.at(x, y) = 0.01f * x - 0.02f * y;
  compute_gradients(img, &gx, &gy);
  EXPECT_NEAR(gx.at(30, 20), 0.01f, 1e-6);
  EXPECT_NEAR(gy.at(30, 20), -0.02f, 1e-6);
  EXPECT_EQ(gx.at(0, 20), 0.f);  // borders are zero
}

TEST(SurfacePixels, ATiltedPlaneIsASurfaceNoiseAndNoDepthAreNot) {
  ImageF rho;
  rho.allocate(64, 48);
  // A plane tilted 45 degrees about the vertical, 1-2 m away: inverse depth linear in x.
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) rho.at(x, y) = 1.0f - 0.5f * x / 63.f;
  const SurfaceCount plane = count_surface_pixels(rho, 2);
  EXPECT_EQ(plane.valid, 23 * 31);  // rows 1, 3 .. 45 and columns 1, 3 .. 61
  EXPECT_EQ(plane.on_surface, plane.valid);
  uint32_t state = 12345;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      state = state * 1664525u + 1013904223u;
      rho.at(x, y) = 0.25f + 2.0f * static_cast<float>(state >> 8) / (1u << 24);  // 0.4-4 m
    }
  const SurfaceCount noise = count_surface_pixels(rho, 2);
  EXPECT_EQ(noise.valid, plane.valid);
  EXPECT_LT(noise.on_surface * 4, noise.valid) << "uniform noise is mostly not a surface";
  rho.fill(0.f);
  const SurfaceCount none = count_surface_pixels(rho, 2);
  EXPECT_EQ(none.valid, 0);
  EXPECT_EQ(none.on_surface, 0);
}

TEST(Canny, FindsTheOutlineOfASquareAsThinEdges) {
  ImageF img;
  ImageU8 edges;
  img.allocate(120, 100);
  edges.allocate(120, 100);
  img.fill(0.2f);
  for (int y = 30; y < 70; ++y)
    for (int x = 40; x < 80; ++x) img.at(x, y) = 0.8f;
  CannyDetector canny;
  canny.allocate(120, 100);
  const int n = canny.detect(img, 20.f, 60.f, &edges);
  // Four sides of 40 px, one pixel thick (give or take the corners).
  EXPECT_GT(n, 4 * 36);
  EXPECT_LT(n, 4 * 44);
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 120; ++x) {
      if (edges.at(x, y) == 0) continue;
      const bool near_x = std::abs(x - 39.5) < 1.6 || std::abs(x - 79.5) < 1.6;
      const bool near_y = std::abs(y - 29.5) < 1.6 || std::abs(y - 69.5) < 1.6;
      EXPECT_TRUE(near_x || near_y) << "edge at " << x << "," << y;
    }
  // Along the middle of the left side, exactly one edge pixel per row.
  for (int y = 40; y < 60; ++y) {
    int row = 0;
    for (int x = 30; x < 50; ++x) row += edges.at(x, y);
    EXPECT_EQ(row, 1) << "row " << y;
  }
}

TEST(Canny, HysteresisKeepsWeakEdgesOnlyWhenConnected) {
  ImageF img;
  ImageU8 edges;
  img.allocate(100, 60);
  edges.allocate(100, 60);
  img.fill(0.5f);
  // A strong step (left) joined to a weak step (right) on the same line, and a separate weak one.
  for (int y = 10; y < 30; ++y)
    for (int x = 0; x < 100; ++x) img.at(x, y) = x < 50 ? 0.9f : 0.56f;
  for (int y = 40; y < 60; ++y)
    for (int x = 0; x < 100; ++x) img.at(x, y) = 0.56f;
  CannyDetector canny;
  canny.allocate(100, 60);
  canny.detect(img, 40.f, 200.f, &edges);
  int weak_connected = 0, weak_isolated = 0;
  for (int x = 60; x < 95; ++x) weak_connected += edges.at(x, 9) + edges.at(x, 10);
  for (int x = 10; x < 90; ++x) weak_isolated += edges.at(x, 39) + edges.at(x, 40);
  EXPECT_GT(weak_connected, 20);
  EXPECT_EQ(weak_isolated, 0);
  ImageF flat;
  flat.allocate(100, 60);
  flat.fill(0.3f);
  EXPECT_EQ(canny.detect(flat, 20.f, 60.f, &edges), 0);
}

}  // namespace
}  // namespace rgbdtam

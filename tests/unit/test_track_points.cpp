// The structure-of-arrays point store the tracker's vectorised loops read.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "rgbdtam/core/track_points.hpp"

namespace rgbdtam {
namespace {

TrackPoint point(int i) {
  TrackPoint p;
  p.x = 0.1f * i;
  p.y = -0.2f * i;
  p.z = 1.f + i;
  p.ref = 0.5f + 0.01f * i;
  for (int k = 0; k < 6; ++k) p.J[k] = static_cast<float>(i * 10 + k);
  return p;
}

TEST(TrackPoints, KeepsEveryFieldAndRefusesBeyondItsCapacity) {
  TrackPoints pts;
  pts.reserve_once(21);
  for (int i = 0; i < 21; ++i) ASSERT_TRUE(pts.push_back(point(i)));
  EXPECT_FALSE(pts.push_back(point(99)));
  ASSERT_EQ(pts.size(), 21);
  for (int i = 0; i < 21; ++i) {
    const TrackPoint p = pts[i];
    const TrackPoint want = point(i);
    EXPECT_EQ(p.x, want.x);
    EXPECT_EQ(p.y, want.y);
    EXPECT_EQ(p.z, want.z);
    EXPECT_EQ(p.ref, want.ref);
    for (int k = 0; k < 6; ++k) EXPECT_EQ(pts.J(k)[i], want.J[k]);
  }
}

TEST(TrackPoints, ArraysAreAlignedAndThePaddingIsFinite) {
  TrackPoints pts;
  pts.reserve_once(13);
  for (int i = 0; i < 13; ++i) ASSERT_TRUE(pts.push_back(point(i)));
  EXPECT_EQ(pts.padded_size(), 16);
  const float* fields[] = {pts.x(), pts.y(), pts.z(), pts.ref(), pts.J(0), pts.J(5)};
  for (const float* f : fields) {
    EXPECT_EQ(reinterpret_cast<uintptr_t>(f) % TrackPoints::kAlignBytes, 0u);
    // Loops run to padded_size(): the padding must not turn a zero weight into a NaN.
    for (int i = pts.size(); i < pts.padded_size(); ++i) EXPECT_TRUE(std::isfinite(f[i]));
  }
  pts.clear();
  EXPECT_EQ(pts.padded_size(), 0);
  EXPECT_TRUE(pts.empty());
}

}  // namespace
}  // namespace rgbdtam

#pragma once
// The units and measures tests state their checks in.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "rgbdtam/core/se3.hpp"

namespace rgbdtam::testing {

constexpr double kDeg = M_PI / 180.0;
constexpr int64_t kMs = 1'000'000;  // in nanoseconds

// The estimate is within `metres` and `radians` of the truth.
inline void expect_close(const SE3& estimate, const SE3& truth, double metres, double radians) {
  const SE3 d = truth.inverse() * estimate;
  EXPECT_LT(d.translation().norm(), metres);
  EXPECT_LT(so3_log(d.quaternion()).norm(), radians);
}

// How far an estimate is from the truth.
struct PoseError {
  double m = 0.0, rad = 0.0;
};
inline PoseError pose_error(const SE3& estimate, const SE3& truth) {
  const SE3 d = truth.inverse() * estimate;
  return {d.translation().norm(), so3_log(d.quaternion()).norm()};
}

// The value a fraction q of the values lie below (the nearest rank below; q in [0, 1]).
inline double percentile(std::vector<double> values, double q) {
  const size_t i = static_cast<size_t>(q * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(i), values.end());
  return values[i];
}

}  // namespace rgbdtam::testing

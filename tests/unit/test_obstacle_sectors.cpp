// OBSTACLE_DISTANCE's sectors against a wall of known distance and angle: a depth image is
// ray-cast from a camera mounted on the body (link.T_b_c as the boards have it) onto a vertical
// plane, and each sector must hold the plane's nearest horizontal distance within it.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "rgbdtam/core/obstacle_sectors.hpp"

namespace rgbdtam {
namespace {

constexpr double kDepthFactor = 5000.0;
const PinholeIntrinsics kCamera{525.0, 525.0, 319.5, 239.5, 640, 480};
// Forward-looking, 8 cm ahead of and 5 cm above the body's origin (the Raspberry Pi 4 board's).
const SE3 kTbc(Eigen::Quaterniond(0.5, 0.5, 0.5, 0.5), Vector3d(0.08, 0.0, -0.05));

struct Wall {
  double distance_m;  // from the body's origin, along the normal
  double yaw_deg;     // the normal's bearing, clockwise from forward
  Vector3d normal() const {
    const double a = yaw_deg * M_PI / 180.0;
    return Vector3d(std::cos(a), std::sin(a), 0.0);
  }
  // Horizontal distance from the body's origin to the wall along a bearing.
  double range_at(double bearing_deg) const {
    return distance_m / std::cos((bearing_deg - yaw_deg) * M_PI / 180.0);
  }
};

std::vector<uint16_t> render(const Wall& wall) {
  std::vector<uint16_t> depth(static_cast<size_t>(kCamera.width_px) * kCamera.height_px, 0);
  const Vector3d n = wall.normal();
  for (int v = 0; v < kCamera.height_px; ++v) {
    for (int u = 0; u < kCamera.width_px; ++u) {
      const Vector3d ray_c((u - kCamera.cx_px) / kCamera.fx_px, (v - kCamera.cy_px) / kCamera.fy_px,
                           1.0);
      const Vector3d ray_b = kTbc.rotation() * ray_c;
      const double s = (wall.distance_m - n.dot(kTbc.translation())) / n.dot(ray_b);
      if (s > 0)
        depth[static_cast<size_t>(v) * kCamera.width_px + u] =
            static_cast<uint16_t>(std::lround(s * kDepthFactor));  // s is the depth: ray_c.z = 1
    }
  }
  return depth;
}

ObstacleSectorizer sectorizer(const ObstacleOptions& options) {
  ObstacleSectorizer s;
  s.init(kCamera, kTbc, kDepthFactor, DepthRange{0.3, 5.0}, options);
  return s;
}

TEST(ObstacleSectors, EachSectorHoldsTheWallsNearestDistanceWithinIt) {
  const ObstacleSectorizer s = sectorizer(ObstacleOptions());
  for (const Wall wall : {Wall{2.0, 0.0}, Wall{1.5, 20.0}, Wall{2.0, -30.0}}) {
    const std::vector<uint16_t> depth = render(wall);
    ObstacleSectors out;
    const auto t0 = std::chrono::steady_clock::now();
    s.measure(depth.data(), &out);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const double fov = 2.0 * std::atan(320.0 / 525.0) * 180.0 / M_PI;
    EXPECT_NEAR(out.increment_deg, fov / 72, 1e-4);
    EXPECT_NEAR(out.angle_offset_deg, -fov / 2 + fov / 144, 1e-3);
    EXPECT_EQ(out.min_cm, 30);
    EXPECT_EQ(out.max_cm, 500);
    double worst_cm = 0;
    int unknown = 0;
    for (int i = 0; i < ObstacleSectors::kCount; ++i) {
      // The camera sits 8 cm ahead of the body's origin, so from there its view is a little
      // narrower than its own field of view: an outermost sector may hold no point.
      if (out.distance_cm[i] == ObstacleSectors::kUnknown && (i < 2 || i >= 70)) {
        ++unknown;
        continue;
      }
      const double from = out.angle_offset_deg + (i - 0.5) * out.increment_deg;
      const double to = from + out.increment_deg;
      // The nearest point of the wall within the sector: at the bearing closest to its normal.
      const double nearest_bearing = std::min(std::max(wall.yaw_deg, from), to);
      const double expected_cm = 100.0 * wall.range_at(nearest_bearing);
      ASSERT_LT(out.distance_cm[i], out.max_cm) << "sector " << i;
      const double error_cm = out.distance_cm[i] - expected_cm;
      worst_cm = std::max(worst_cm, std::fabs(error_cm));
      // Samples are 4 px (0.44 degrees) apart: the nearest one misses the sector's best by up
      // to the wall's slope across that angle, more where the wall is seen obliquely.
      const double slope = std::tan(std::fabs(nearest_bearing - wall.yaw_deg) * M_PI / 180.0);
      const double allowed_cm = 1.0 + expected_cm * slope * 4.0 / kCamera.fx_px;
      EXPECT_GT(error_cm, -1.0) << "sector " << i << ", wall " << wall.yaw_deg;
      EXPECT_LT(error_cm, allowed_cm) << "sector " << i << ", wall " << wall.yaw_deg;
    }
    EXPECT_LE(unknown, 2);
    std::printf(
        "wall at %.1f m, normal %+.0f deg: worst sector error %.2f cm, %d outermost "
        "sectors unseen; measured in %.3f ms\n",
        wall.distance_m, wall.yaw_deg, worst_cm, unknown, ms);
  }
}

TEST(ObstacleSectors, NothingInTheBandIsNoObstacleAndNoDepthIsUnknown) {
  ObstacleOptions high;
  high.lowest_m = 3.0;  // above anything the camera sees of a wall 2 m away
  high.highest_m = 4.0;
  const std::vector<uint16_t> wall = render(Wall{2.0, 0.0});
  ObstacleSectors out;
  sectorizer(high).measure(wall.data(), &out);
  int nothing = 0;
  for (const uint16_t d : out.distance_cm) {
    EXPECT_TRUE(d == out.max_cm + 1 || d == ObstacleSectors::kUnknown) << d;
    nothing += d == out.max_cm + 1;
  }
  EXPECT_GE(nothing, ObstacleSectors::kCount - 2);

  const std::vector<uint16_t> none(wall.size(), 0);
  sectorizer(ObstacleOptions()).measure(none.data(), &out);
  for (const uint16_t d : out.distance_cm) EXPECT_EQ(d, ObstacleSectors::kUnknown);
}

// The wall closing in at 3 m/s, reported at 10 Hz: 1 m, 0.45 m, then nearer than the sensor's
// 0.3 m minimum, where a structured-light sensor gives no depth at all. PX4 with CP_GO_NO_DATA
// moves into a sector read as unknown: these read the minimum until depth returns.
TEST(ObstacleSectors, AWallThatBlindsTheSensorReadsTheMinimumNotUnknown) {
  const ObstacleSectorizer s = sectorizer(ObstacleOptions());
  BlindedSectors blinded;
  blinded.init(3.0);  // health.max_speed: 30 cm between reports
  const std::vector<uint16_t> blind(static_cast<size_t>(kCamera.width_px) * kCamera.height_px, 0);
  ObstacleSectors out, before;
  for (const double d : {1.0, 0.45}) {
    s.measure(render(Wall{d, 0.0}).data(), &out);
    blinded.mark(0.1, &out);
  }
  before = out;
  int blinded_sectors = 0;
  for (int report = 0; report < 3; ++report) {
    s.measure(blind.data(), &out);
    blinded.mark(0.1, &out);
    for (int i = 0; i < ObstacleSectors::kCount; ++i) {
      const uint16_t last = before.distance_cm[i];
      const bool near = last != ObstacleSectors::kUnknown && last <= out.min_cm + 30;
      EXPECT_EQ(out.distance_cm[i], near ? out.min_cm : ObstacleSectors::kUnknown)
          << "report " << report << ", sector " << i << ", last " << last;
      blinded_sectors += report == 0 && near;
    }
  }
  int seen = 0;
  for (const uint16_t d : before.distance_cm) seen += d != ObstacleSectors::kUnknown;
  // From the body's origin, 8 cm behind the camera, the wall spans the middle 52 degrees.
  EXPECT_EQ(blinded_sectors, seen) << "every sector that saw the wall at 0.45 m";
  EXPECT_GE(seen, ObstacleSectors::kCount * 3 / 4);
  // Depth back: the wall's distance again.
  s.measure(render(Wall{0.45, 0.0}).data(), &out);
  blinded.mark(0.1, &out);
  EXPECT_EQ(out.distance_cm[ObstacleSectors::kCount / 2], before.distance_cm[36]);
}

TEST(ObstacleSectors, NoDepthWithoutANearObstacleBeforeItIsUnknownAndAReadingBelowTheMinimumIsIt) {
  const ObstacleSectorizer s = sectorizer(ObstacleOptions());
  const std::vector<uint16_t> blind(static_cast<size_t>(kCamera.width_px) * kCamera.height_px, 0);
  ObstacleSectors out;
  // Blind from the first report: nothing says what is there.
  BlindedSectors from_start;
  from_start.init(3.0);
  s.measure(blind.data(), &out);
  from_start.mark(0.1, &out);
  for (const uint16_t d : out.distance_cm) EXPECT_EQ(d, ObstacleSectors::kUnknown);
  // Last seen 2 m away: no surface can have come within the minimum since (the view turned away,
  // or opened onto nothing in range).
  BlindedSectors far;
  far.init(3.0);
  s.measure(render(Wall{2.0, 0.0}).data(), &out);
  far.mark(0.1, &out);
  s.measure(blind.data(), &out);
  far.mark(0.1, &out);
  for (const uint16_t d : out.distance_cm) EXPECT_EQ(d, ObstacleSectors::kUnknown);
  // A sensor that does read nearer than its minimum: an obstacle there, at the minimum. (The
  // wall 12 cm before the camera, which sits 8 cm ahead of the body's origin, spans only the
  // middle sectors as seen from that origin.)
  s.measure(render(Wall{0.2, 0.0}).data(), &out);
  int at_minimum = 0;
  for (const uint16_t d : out.distance_cm) {
    EXPECT_TRUE(d == out.min_cm || d == ObstacleSectors::kUnknown) << d;
    at_minimum += d == out.min_cm;
  }
  EXPECT_GE(at_minimum, ObstacleSectors::kCount / 2);
}

TEST(ObstacleSectors, AConfiguredSpanIsCentredOnTheCamerasBearing) {
  ObstacleOptions wide;
  wide.fov_deg = 90.0;
  // The camera turned 30 degrees right on the body.
  const SE3 yawed =
      SE3(Eigen::Quaterniond(Eigen::AngleAxisd(30.0 * M_PI / 180.0, Vector3d::UnitZ())),
          Vector3d::Zero()) *
      kTbc;
  ObstacleSectorizer s;
  s.init(kCamera, yawed, kDepthFactor, DepthRange{0.3, 5.0}, wide);
  const std::vector<uint16_t> depth(static_cast<size_t>(kCamera.width_px) * kCamera.height_px,
                                    10000);
  ObstacleSectors out;
  s.measure(depth.data(), &out);
  EXPECT_NEAR(out.increment_deg, 1.25, 1e-5);
  EXPECT_NEAR(out.angle_offset_deg, 30.0 - 45.0 + 0.625, 1e-3);
  // A span wider than the camera's: the sectors it cannot see are unknown.
  EXPECT_EQ(out.distance_cm[0], ObstacleSectors::kUnknown);
  EXPECT_EQ(out.distance_cm[71], ObstacleSectors::kUnknown);
  EXPECT_LT(out.distance_cm[36], out.max_cm);
}

}  // namespace
}  // namespace rgbdtam

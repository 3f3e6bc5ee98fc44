// Depth registration against depth rendered exactly in both cameras: a plate 1 m away in front
// of a wall at 2 m, seen by a depth camera 2.5 cm to the side of the colour camera, with another
// focal length, lens distortion and a small rotation.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "measures.hpp"
#include "rgbdtam/core/depth_registration.hpp"

namespace rgbdtam {
namespace {

constexpr double kFactor = 5000.0;  // raw units per metre
constexpr double kPlateZ = 1.0, kWallZ = 2.0;
constexpr double kPlateHalfX = 0.15, kPlateHalfY = 0.10;

// The nearest surface along the ray origin + s * direction (colour camera's frame); its point.
bool cast(const Vector3d& origin, const Vector3d& direction, Vector3d* hit) {
  for (const double z : {kPlateZ, kWallZ}) {
    const double s = (z - origin.z()) / direction.z();
    const Vector3d p = origin + s * direction;
    const bool on_plate = std::abs(p.x()) <= kPlateHalfX && std::abs(p.y()) <= kPlateHalfY;
    if (s > 0 && (z == kWallZ || on_plate)) {
      *hit = p;
      return true;
    }
  }
  return false;
}

// Raw depth as `camera` (at T_c_cam in the colour camera's frame) sees the scene.
std::vector<uint16_t> render(const CameraModel& camera, const SE3& T_c_cam) {
  const PinholeIntrinsics& k = camera.intrinsics;
  std::vector<uint16_t> depth(static_cast<size_t>(k.width_px * k.height_px), 0);
  const SE3 T_cam_c = T_c_cam.inverse();
  for (int y = 0; y < k.height_px; ++y) {
    for (int x = 0; x < k.width_px; ++x) {
      double xn = 0, yn = 0;
      camera.distortion.undistort((x - k.cx_px) / k.fx_px, (y - k.cy_px) / k.fy_px, &xn, &yn);
      Vector3d hit;
      if (!cast(T_c_cam.translation(), T_c_cam.rotation() * Vector3d(xn, yn, 1), &hit)) {
        continue;
      }
      const double z = (T_cam_c * hit).z();
      depth[static_cast<size_t>(y * k.width_px + x)] =
          static_cast<uint16_t>(std::lround(z * kFactor));
    }
  }
  return depth;
}

// The colour pixels whose surface the depth camera sees too (inside its image, not hidden
// behind the plate): exact_c is the colour camera's exact depth, measured the depth camera's.
std::vector<bool> seen_by_depth_camera(const std::vector<uint16_t>& exact_c,
                                       const CameraModel& colour,
                                       const std::vector<uint16_t>& measured,
                                       const CameraModel& depth_camera, const SE3& T_c_d) {
  const PinholeIntrinsics& kc = colour.intrinsics;
  const PinholeIntrinsics& kd = depth_camera.intrinsics;
  const SE3 T_d_c = T_c_d.inverse();
  std::vector<bool> seen(exact_c.size(), false);
  for (int y = 0; y < kc.height_px; ++y) {
    for (int x = 0; x < kc.width_px; ++x) {
      const size_t i = static_cast<size_t>(y * kc.width_px + x);
      if (exact_c[i] == 0) continue;
      const double z = exact_c[i] / kFactor;
      const Vector3d p_d =
          T_d_c * Vector3d((x - kc.cx_px) / kc.fx_px * z, (y - kc.cy_px) / kc.fy_px * z, z);
      double xd = 0, yd = 0;
      depth_camera.distortion.distort(p_d.x() / p_d.z(), p_d.y() / p_d.z(), &xd, &yd);
      const long u = std::lround(kd.fx_px * xd + kd.cx_px);
      const long v = std::lround(kd.fy_px * yd + kd.cy_px);
      if (u < 0 || v < 0 || u >= kd.width_px || v >= kd.height_px) continue;
      const uint16_t there = measured[static_cast<size_t>(v * kd.width_px + u)];
      seen[i] = std::abs(there / kFactor - p_d.z()) < 0.05;
    }
  }
  return seen;
}

struct Comparison {
  std::vector<double> errors_m;  // where both have depth and the depth camera sees it
  int seen = 0, filled = 0, unseen = 0, unseen_filled = 0, wrong_surface = 0;
};

Comparison compare(const std::vector<uint16_t>& registered, const std::vector<uint16_t>& exact,
                   const std::vector<bool>& seen) {
  Comparison c;
  for (size_t i = 0; i < exact.size(); ++i) {
    if (exact[i] == 0) continue;
    if (!seen[i]) {
      ++c.unseen;
      c.unseen_filled += registered[i] != 0 ? 1 : 0;
      continue;
    }
    ++c.seen;
    if (registered[i] == 0) continue;
    ++c.filled;
    const double error = std::abs(registered[i] - exact[i]) / kFactor;
    c.errors_m.push_back(error);
    c.wrong_surface += error > 0.5 ? 1 : 0;  // the plate where the wall is, or the reverse
  }
  return c;
}

// The scene rendered exactly in both cameras, the depth camera's registered into the colour
// camera, and compared with the colour camera's.
Comparison register_and_compare(const CameraModel& depth_camera, const CameraModel& colour,
                                const SE3& T_c_d) {
  const std::vector<uint16_t> measured = render(depth_camera, T_c_d);
  const std::vector<uint16_t> exact = render(colour, SE3());
  DepthRegistration registration;
  registration.init(depth_camera, colour, T_c_d, kFactor);
  std::vector<uint16_t> registered(exact.size(), 1);
  registration.apply(measured.data(), registered.data());
  return compare(registered, exact,
                 seen_by_depth_camera(exact, colour, measured, depth_camera, T_c_d));
}

using testing::percentile;

class Registration : public ::testing::Test {
 protected:
  void SetUp() override {
    colour_.intrinsics = {262.0, 262.5, 159.5, 119.5, 320, 240};
    depth_camera_.intrinsics = {290.0, 290.0, 161.0, 118.0, 320, 240};
    depth_camera_.distortion.k1 = -0.08;
    depth_camera_.distortion.k2 = 0.02;
    depth_camera_.distortion.p1 = 0.001;
    // 2.5 cm to the side, under a degree of rotation.
    T_c_d_ = SE3(so3_exp(Vector3d(0.004, -0.009, 0.003)), Vector3d(0.025, 0.002, -0.001));
  }
  CameraModel colour_, depth_camera_;
  SE3 T_c_d_;
};

TEST_F(Registration, DepthFromItsOwnCameraLandsWhereTheColourCameraSeesIt) {
  const Comparison c = register_and_compare(depth_camera_, colour_, T_c_d_);
  const double median = percentile(c.errors_m, 0.5), p95 = percentile(c.errors_m, 0.95);
  std::printf(
      "registered: %d of the %d pixels both cameras see filled (%.2f %%), error median %.2f mm, "
      "p95 %.2f mm, %d on the wrong surface; %d of the %d only the colour camera sees filled\n",
      c.filled, c.seen, 100.0 * c.filled / c.seen, median * 1e3, p95 * 1e3, c.wrong_surface,
      c.unseen_filled, c.unseen);
  // Raw units are 0.2 mm; a pixel's square is 3.5 mm wide at 1 m and tilts by under a degree.
  EXPECT_LT(median, 0.0005);
  EXPECT_LT(p95, 0.002);
  // What both cameras see is filled: no cracks between the squares.
  EXPECT_GT(c.filled, c.seen * 999 / 1000);
  // What the depth camera does not see stays a hole: its own image's edge, and the wall hidden
  // behind the plate's edge (a strip about 3 px wide: 2.5 cm x 262 px x (1/1 m - 1/2 m)); only
  // pixels along those outlines may take a neighbour's depth. The plate's outline is 260 px,
  // the depth camera's field's about 1 000.
  EXPECT_GT(c.unseen, 1000);
  EXPECT_LT(c.unseen_filled, 1260);
  // Nearest wins: across the plate's outline, at most one pixel in ten is the other surface.
  EXPECT_LT(c.wrong_surface, 26);
}

// A D4xx's depth camera has an image of its own size and a wider field than colour's (87 against
// 69 degrees): a wider, larger image, and a coarser one whose pixels each cover about two of
// colour's, both land as the colour camera sees the scene, without cracks.
TEST_F(Registration, ADepthImageOfAnotherSizeLandsInTheColourCamera) {
  struct Shape {
    const char* name;
    PinholeIntrinsics intrinsics;
  };
  const Shape shapes[] = {
      {"424x240, 88 degrees wide", {220.0, 220.0, 213.5, 118.0, 424, 240}},
      {"160x120, half colour's focal length", {131.0, 131.0, 80.5, 58.5, 160, 120}}};
  for (const Shape& shape : shapes) {
    CameraModel depth_camera = depth_camera_;
    depth_camera.intrinsics = shape.intrinsics;
    const Comparison c = register_and_compare(depth_camera, colour_, T_c_d_);
    const double median = percentile(c.errors_m, 0.5), p95 = percentile(c.errors_m, 0.95);
    std::printf(
        "%s: %d of the %d pixels both see filled, error median %.2f mm, p95 %.2f mm, %d "
        "on the wrong surface\n",
        shape.name, c.filled, c.seen, median * 1e3, p95 * 1e3, c.wrong_surface);
    EXPECT_LT(median, 0.0005) << shape.name;
    EXPECT_LT(p95, 0.002) << shape.name;
    EXPECT_GT(c.filled, c.seen * 999 / 1000) << shape.name;
    EXPECT_LT(c.wrong_surface, 52) << shape.name;
  }
}

// A wall receding steeply to the side (70 degrees from facing the cameras), 5 cm of baseline:
// the depth camera sees it 13 % wider than the colour camera does. With squares of their facing
// size, 12 % of the wall's pixels were cracks, in runs of 5-6 every 50 pixels where the
// stretch keeps neighbouring squares apart; the slant margin closes them.
TEST_F(Registration, ASteeplySlantedWallLeavesNoCrack) {
  const Vector3d normal(-std::sin(70.0 * M_PI / 180.0), 0.0, -std::cos(70.0 * M_PI / 180.0));
  const Vector3d on_wall(0.0, 0.0, 1.2);
  const SE3 T_c_d(Eigen::Quaterniond::Identity(), Vector3d(0.05, 0.0, 0.0));
  CameraModel pinhole = depth_camera_;
  pinhole.distortion = RadTanDistortion();
  auto wall = [&](const CameraModel& camera, const SE3& T_c_cam) {
    const PinholeIntrinsics& k = camera.intrinsics;
    std::vector<uint16_t> depth(static_cast<size_t>(k.width_px * k.height_px), 0);
    for (int y = 0; y < k.height_px; ++y) {
      for (int x = 0; x < k.width_px; ++x) {
        const Vector3d ray((x - k.cx_px) / k.fx_px, (y - k.cy_px) / k.fy_px, 1.0);
        const Vector3d o = T_c_cam.translation();
        const double s = normal.dot(on_wall - o) / normal.dot(ray);  // no rotation: z = s
        if (s > 0.3 && s < 6.0) {
          depth[static_cast<size_t>(y * k.width_px + x)] =
              static_cast<uint16_t>(std::lround(s * kFactor));
        }
      }
    }
    return depth;
  };
  const std::vector<uint16_t> measured = wall(pinhole, T_c_d), exact = wall(colour_, SE3());
  DepthRegistration registration;
  registration.init(pinhole, colour_, T_c_d, kFactor);
  std::vector<uint16_t> registered(exact.size(), 1);
  registration.apply(measured.data(), registered.data());
  const Comparison c =
      compare(registered, exact, seen_by_depth_camera(exact, colour_, measured, pinhole, T_c_d));
  std::printf("slanted wall: %d of the %d pixels both cameras see filled, error median %.2f mm\n",
              c.filled, c.seen, percentile(c.errors_m, 0.5) * 1e3);
  EXPECT_GT(c.seen, 40000);
  EXPECT_GT(c.filled, c.seen * 999 / 1000);
  EXPECT_EQ(c.wrong_surface, 0);
  // Each filled pixel holds its square's depth: off by up to half a pixel's step along the
  // slant, which grows with depth (3 cm at 1.7 m, 11 cm at 3.6 m).
  EXPECT_LT(percentile(c.errors_m, 0.5), 0.01);
}

TEST_F(Registration, TheSameCameraGivesTheSameImage) {
  const std::vector<uint16_t> exact = render(colour_, SE3());
  DepthRegistration registration;
  registration.init(colour_, colour_, SE3(), kFactor);
  std::vector<uint16_t> registered(exact.size(), 1);
  registration.apply(exact.data(), registered.data());
  EXPECT_EQ(registered, exact);
}

TEST_F(Registration, PixelsWithoutDepthStayHolesAndMakeNone) {
  std::vector<uint16_t> measured = render(depth_camera_, T_c_d_);
  // A square without depth in the middle of the plate: no depth comes from it, and it does not
  // hide the wall (there is nothing behind a plate).
  const int w = depth_camera_.intrinsics.width_px;
  for (int y = 110; y < 130; ++y) {
    for (int x = 150; x < 170; ++x) measured[static_cast<size_t>(y * w + x)] = 0;
  }
  DepthRegistration registration;
  registration.init(depth_camera_, colour_, T_c_d_, kFactor);
  std::vector<uint16_t> registered(measured.size(), 1);
  registration.apply(measured.data(), registered.data());
  int holes_in_the_middle = 0, wall = 0;
  for (int y = 105; y < 135; ++y) {
    for (int x = 140; x < 180; ++x) {
      const uint16_t d = registered[static_cast<size_t>(y * colour_.intrinsics.width_px + x)];
      holes_in_the_middle += d == 0 ? 1 : 0;
      wall += d > 1.5 * kFactor ? 1 : 0;
    }
  }
  EXPECT_GT(holes_in_the_middle, 15 * 15);
  EXPECT_EQ(wall, 0);
}

}  // namespace
}  // namespace rgbdtam

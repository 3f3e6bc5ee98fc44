#include "synthetic_scene.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdtam::testing {
namespace {
struct Hit {
  double t = 1e30;  // ray parameter (camera z for unit-z rays)
  double u = 0, v = 0;
};

struct Plane {
  Vector3d n;  // unit normal
  double d;    // n . x = d
  Vector3d u_axis, v_axis;
  Vector3d lo, hi;  // bounding box of the valid region
  double phase;
};

double texture(double u, double v, double phase) {
  const double k = 2.0 * M_PI;
  // Sharp-edged checker (edges for Canny) plus smooth blobs (gradients everywhere).
  const double checker = std::tanh(6.0 * std::sin(k * u / 0.3 + phase)) *
                         std::tanh(6.0 * std::sin(k * v / 0.3 + 0.5 * phase));
  const double blobs = std::sin(k * u / 0.7 + 1.3 * phase) * std::cos(k * v / 0.55 - phase);
  return 0.5 + 0.28 * checker + 0.15 * blobs;
}

std::vector<Plane> scene_planes(bool with_box) {
  std::vector<Plane> planes;
  auto add = [&](Vector3d n, double d, Vector3d ua, Vector3d va, Vector3d lo, Vector3d hi,
                 double phase) { planes.push_back({n, d, ua, va, lo, hi, phase}); };
  const double inf = 1e9;
  const Vector3d X(1, 0, 0), Y(0, 1, 0), Z(0, 0, 1);
  add(-Z, -3.0, X, Y, Vector3d(-inf, -inf, 2.99), Vector3d(inf, inf, 3.01), 0.0);     // back wall
  add(-Y, -0.7, X, Z, Vector3d(-inf, 0.69, -inf), Vector3d(inf, 0.71, inf), 1.0);     // floor
  add(X, -1.3, Z, Y, Vector3d(-1.31, -inf, -inf), Vector3d(-1.29, inf, inf), 2.0);    // left wall
  add(-X, -1.5, Z, Y, Vector3d(1.49, -inf, -inf), Vector3d(1.51, inf, inf), 5.0);     // right wall
  if (with_box) {
    add(-Z, -1.6, X, Y, Vector3d(-0.5, -0.2, 1.59), Vector3d(0.1, 0.4, 1.61), 3.0);   // box front
    add(X, 0.1, Z, Y, Vector3d(0.09, -0.2, 1.6), Vector3d(0.11, 0.4, 2.2), 4.0);      // box side
  }
  return planes;
}
}  // namespace

SE3 SyntheticScene::pose_at(double t) {
  const Vector3d p(0.10 * std::sin(0.9 * t), 0.05 * std::sin(1.7 * t), 0.08 * (1.0 - std::cos(0.6 * t)));
  const Vector3d w(0.03 * std::sin(1.1 * t), 0.05 * std::sin(0.7 * t), 0.02 * std::sin(1.3 * t));
  return SE3(so3_exp(w), p);
}

SyntheticFrame SyntheticScene::render(const SE3& T_w_c) const {
  const std::vector<Plane> planes = scene_planes(with_box);
  const int w = camera.width_px, h = camera.height_px;
  SyntheticFrame f;
  f.gray.resize(static_cast<size_t>(w) * h);
  f.depth.resize(static_cast<size_t>(w) * h);
  const Matrix3d R = T_w_c.rotation();
  const Vector3d o = T_w_c.translation();
  auto cast = [&](double px, double py, Hit* best) {
    const Vector3d ray_c((px - camera.cx_px) / camera.fx_px, (py - camera.cy_px) / camera.fy_px, 1.0);
    const Vector3d ray_w = R * ray_c;
    for (const Plane& pl : planes) {
      const double denom = pl.n.dot(ray_w);
      if (std::fabs(denom) < 1e-12) continue;
      const double t = (pl.d - pl.n.dot(o)) / denom;
      if (t <= 0.01 || t >= best->t) continue;
      const Vector3d x = o + t * ray_w;
      if ((x.array() < pl.lo.array()).any() || (x.array() > pl.hi.array()).any()) continue;
      best->t = t;
      best->u = texture(x.dot(pl.u_axis), x.dot(pl.v_axis), pl.phase);
    }
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double sum = 0;
      for (int s = 0; s < 4; ++s) {
        Hit hit;
        cast(x - 0.25 + 0.5 * (s & 1), y - 0.25 + 0.5 * (s >> 1), &hit);
        sum += hit.t < 1e29 ? hit.u : 0.0;
      }
      Hit centre;
      cast(x, y, &centre);
      const size_t i = static_cast<size_t>(y) * w + x;
      f.gray[i] = static_cast<uint8_t>(std::clamp(std::lround(sum / 4.0 * 255.0), 0L, 255L));
      const bool measured = centre.t < max_depth_m;
      f.depth[i] = measured ? static_cast<uint16_t>(std::lround(centre.t * depth_factor)) : 0;
    }
  }
  return f;
}

}  // namespace rgbdtam::testing

#include "synthetic_scene.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <tuple>

namespace rgbdtam::testing {
namespace {
struct PlaneHit {
  double t = 1e30;  // ray parameter (camera z for unit-z rays)
  double u = 0, v = 0;
};

struct Plane {
  Vector3d n;  // unit normal
  double d;    // n . x = d
  Vector3d u_axis, v_axis;
  Vector3d lo, hi;  // bounding box of the valid region
  double phase;
  // A plain plane: this grey, with a faint ripple, and a dark mark (0.4 x 0.6 m) every
  // mark_spacing_m along u (0: none) instead of the textured one's checker and blobs.
  double plain_grey = -1.0;
  double mark_spacing_m = 0.0;
};

// tanh from one exp: std::tanh goes through expm1, a fifth of a render's time; the difference
// (about 1e-16) leaves every grey level of every rendered scene the same.
double tanh_by_exp(double x) {
  const double e = std::exp(2.0 * x);
  return (e - 1.0) / (e + 1.0);
}

double texture(double u, double v, double phase) {
  const double k = 2.0 * M_PI;
  // Sharp-edged checker (edges for Canny) plus smooth blobs (gradients everywhere).
  const double checker = tanh_by_exp(6.0 * std::sin(k * u / 0.3 + phase)) *
                         tanh_by_exp(6.0 * std::sin(k * v / 0.3 + 0.5 * phase));
  const double blobs = std::sin(k * u / 0.7 + 1.3 * phase) * std::cos(k * v / 0.55 - phase);
  return 0.5 + 0.28 * checker + 0.15 * blobs;
}

double shade(const Plane& pl, double u, double v) {
  if (pl.plain_grey < 0.0) return texture(u, v, pl.phase);
  // A ripple of 1.5 grey levels: paint is never perfectly even, and a real sensor's noise is
  // larger still.
  double value = pl.plain_grey + 0.006 * std::sin(2.0 * M_PI * u / 1.3 + pl.phase) *
                                     std::sin(2.0 * M_PI * v / 0.9 - pl.phase);
  if (pl.mark_spacing_m > 0.0) {
    const double along = u - pl.mark_spacing_m * std::floor(u / pl.mark_spacing_m);
    const double across = v - pl.phase * 0.1;
    if (along < 0.4 && across > 0.0 && across < 0.6) value = 0.5 * pl.plain_grey;
  }
  return value;
}

std::vector<Plane> degenerate_planes(SyntheticScene::Layout layout) {
  std::vector<Plane> planes;
  const Vector3d X(1, 0, 0), Y(0, 1, 0), Z(0, 0, 1);
  auto add = [&](Vector3d n, double d, Vector3d ua, Vector3d va, Vector3d lo, Vector3d hi,
                 double phase, double grey, double marks) {
    Plane pl{n, d, ua, va, lo, hi, phase};
    pl.plain_grey = grey;
    pl.mark_spacing_m = marks;
    planes.push_back(pl);
  };
  if (layout == SyntheticScene::Layout::kCorridor) {
    // Along +z from z = -2 m to the end wall at 40 m, beyond the sensor's range.
    const double left = -0.6, right = 0.9, floor = 1.0, ceiling = -0.5;
    add(X, left, Z, Y, Vector3d(left - 0.01, ceiling, -2), Vector3d(left + 0.01, floor, 40), 1.0,
        0.6, 2.5);
    add(-X, -right, Z, Y, Vector3d(right - 0.01, ceiling, -2), Vector3d(right + 0.01, floor, 40),
        4.0, 0.55, 3.1);
    add(-Y, -floor, Z, X, Vector3d(left, floor - 0.01, -2), Vector3d(right, floor + 0.01, 40), 2.0,
        0.35, 0.0);
    add(Y, ceiling, Z, X, Vector3d(left, ceiling - 0.01, -2), Vector3d(right, ceiling + 0.01, 40),
        3.0, 0.8, 0.0);
    add(-Z, -40.0, X, Y, Vector3d(left, ceiling, 39.99), Vector3d(right, floor, 40.01), 5.0, 0.5,
        0.0);
  } else {
    // A room 4 m wide, 2.5 m high, 4 m deep around the camera's circle.
    const double x0 = -2.0, x1 = 2.0, floor = 1.2, ceiling = -1.3, z0 = -1.0, z1 = 3.0;
    add(X, x0, Z, Y, Vector3d(x0 - 0.01, ceiling, z0), Vector3d(x0 + 0.01, floor, z1), 1.0, 0.6,
        1.7);
    add(-X, -x1, Z, Y, Vector3d(x1 - 0.01, ceiling, z0), Vector3d(x1 + 0.01, floor, z1), 2.0, 0.55,
        2.3);
    add(-Z, -z1, X, Y, Vector3d(x0, ceiling, z1 - 0.01), Vector3d(x1, floor, z1 + 0.01), 3.0, 0.65,
        2.9);
    add(Z, z0, X, Y, Vector3d(x0, ceiling, z0 - 0.01), Vector3d(x1, floor, z0 + 0.01), 4.0, 0.5,
        0.0);
    add(-Y, -floor, X, Z, Vector3d(x0, floor - 0.01, z0), Vector3d(x1, floor + 0.01, z1), 5.0, 0.35,
        0.0);
    add(Y, ceiling, X, Z, Vector3d(x0, ceiling - 0.01, z0), Vector3d(x1, ceiling + 0.01, z1), 6.0,
        0.8, 0.0);
  }
  return planes;
}

std::vector<Plane> scene_planes(bool with_box, bool box_in_corner, bool with_room, double wall_z) {
  std::vector<Plane> planes;
  auto add = [&](Vector3d n, double d, Vector3d ua, Vector3d va, Vector3d lo, Vector3d hi,
                 double phase) {
    planes.push_back({n, d, ua, va, lo, hi, phase});
  };
  const double inf = 1e9;
  const Vector3d X(1, 0, 0), Y(0, 1, 0), Z(0, 0, 1);
  add(-Z, -wall_z, X, Y, Vector3d(-inf, -inf, wall_z - 0.01), Vector3d(inf, inf, wall_z + 0.01),
      0.0);  // back wall
  if (with_room) {
    add(-Y, -0.7, X, Z, Vector3d(-inf, 0.69, -inf), Vector3d(inf, 0.71, inf), 1.0);   // floor
    add(X, -1.3, Z, Y, Vector3d(-1.31, -inf, -inf), Vector3d(-1.29, inf, inf), 2.0);  // left wall
    add(-X, -1.5, Z, Y, Vector3d(1.49, -inf, -inf), Vector3d(1.51, inf, inf), 5.0);   // right wall
  }
  if (with_box) {
    // Front face (x, y extents) at z = 1.6 m, and the right side face from 1.6 to 2.2 m.
    const double x0 = box_in_corner ? -1.3 : -0.5, x1 = box_in_corner ? -0.35 : 0.1;
    const double y0 = box_in_corner ? 0.1 : -0.2, y1 = box_in_corner ? 0.9 : 0.4;
    add(-Z, -1.6, X, Y, Vector3d(x0, y0, 1.59), Vector3d(x1, y1, 1.61), 3.0);
    add(X, x1, Z, Y, Vector3d(x1 - 0.01, y0, 1.6), Vector3d(x1 + 0.01, y1, 2.2), 4.0);
  }
  return planes;
}
}  // namespace

SE3 SyntheticScene::pose_at(double t) {
  const Vector3d p(0.10 * std::sin(0.9 * t), 0.05 * std::sin(1.7 * t),
                   0.08 * (1.0 - std::cos(0.6 * t)));
  const Vector3d w(0.03 * std::sin(1.1 * t), 0.05 * std::sin(0.7 * t), 0.02 * std::sin(1.3 * t));
  return SE3(so3_exp(w), p);
}

SE3 SyntheticScene::camera_at(double t) const {
  if (layout == Layout::kCorridor) {
    // 2.4 m/s along the corridor, the view swinging +-5 degrees at up to 30 deg/s.
    constexpr double kSwingRad = 5.0 * M_PI / 180.0, kSwingRate = 6.0;
    return SE3(so3_exp(Vector3d(0.3 * kSwingRad * std::sin(1.3 * kSwingRate * t),
                                kSwingRad * std::sin(kSwingRate * t), 0.0)),
               Vector3d(0.05 * std::sin(2.0 * t), 0.03 * std::sin(3.0 * t), 2.4 * t));
  }
  if (layout == Layout::kPlainRoom) {
    // A circle of 0.6 m radius at 2.4 m/s while the view turns at 30 deg/s (1 degree a frame).
    constexpr double kRadius = 0.6, kCircleRate = 4.0, kTurnRate = 30.0 * M_PI / 180.0;
    const double a = kCircleRate * t;
    return SE3(
        so3_exp(Vector3d(0.0, kTurnRate * t, 0.0)),
        Vector3d(kRadius * std::sin(a), 0.05 * std::sin(2.0 * t), 1.0 - kRadius * std::cos(a)));
  }
  if (pan_peak_deg_s > 0.0) {
    constexpr double kYawAmplitude = 35.0 * M_PI / 180.0;
    const double w = pan_peak_deg_s * M_PI / 180.0 / kYawAmplitude;  // peak = amplitude * w
    const double yaw = kYawAmplitude * std::sin(w * t);
    const double pitch = 0.25 * kYawAmplitude * std::sin(1.7 * w * t);
    return SE3(
        so3_exp(Vector3d(pitch, yaw, 0.0)),
        Vector3d(0.03 * std::sin(2.3 * t), 0.02 * std::sin(3.1 * t), 0.02 * std::sin(1.9 * t)));
  }
  if (!diagonal_path) return pose_at(t);
  return SE3(so3_exp(Vector3d(0.01 * std::sin(2 * t), 0.01 * std::sin(3 * t), 0.0)),
             Vector3d(0.45 * t, -0.45 * t, 0.05 * t));
}

SyntheticFrame SyntheticScene::render(const SE3& T_w_c) const {
  return render_rows([&](int) { return T_w_c; });
}

SyntheticFrame SyntheticScene::render_rows(const std::function<SE3(int)>& T_w_c_of_row) const {
  const std::vector<Plane> planes =
      layout == Layout::kTexturedRoom
          ? scene_planes(with_box, box_in_corner, with_room, back_wall_z_m)
          : degenerate_planes(layout);
  const int w = camera.width_px, h = camera.height_px;
  SyntheticFrame f;
  f.gray.resize(static_cast<size_t>(w) * h);
  f.depth.resize(static_cast<size_t>(w) * h);
  Matrix3d R;
  Vector3d o;
  // Per plane, the ray terms that do not depend on the pixel.
  struct Prepared {
    double n_dot_rx, n_dot_ry, n_dot_r1, numerator;
  };
  std::vector<Prepared> prep(planes.size());
  auto prepare = [&](const SE3& T_w_c) {
    R = T_w_c.rotation();
    o = T_w_c.translation();
    for (size_t k = 0; k < planes.size(); ++k) {
      const Vector3d nr = R.transpose() * planes[k].n;  // n . (R ray_c) = (R^T n) . ray_c
      prep[k] = {nr.x(), nr.y(), nr.z(), planes[k].d - planes[k].n.dot(o)};
    }
  };
  // Returns the texture value and writes the ray depth (camera z) of the nearest hit. Only that
  // hit is shaded: the texture's sines take most of the rendering (under qemu, most of a test).
  auto cast = [&](double px, double py, double* depth) {
    const double rx = (px - camera.cx_px) / camera.fx_px, ry = (py - camera.cy_px) / camera.fy_px;
    double best = 1e30;
    const Plane* nearest = nullptr;
    Vector3d nearest_x;
    for (size_t k = 0; k < planes.size(); ++k) {
      const Prepared& q = prep[k];
      const double denom = q.n_dot_rx * rx + q.n_dot_ry * ry + q.n_dot_r1;
      if (std::fabs(denom) < 1e-12) continue;
      const double t = q.numerator / denom;
      if (t <= 0.01 || t >= best) continue;
      const Vector3d x = o + t * (R * Vector3d(rx, ry, 1.0));
      const Plane& pl = planes[k];
      if ((x.array() < pl.lo.array()).any() || (x.array() > pl.hi.array()).any()) continue;
      best = t;
      nearest = &pl;
      nearest_x = x;
    }
    *depth = best;
    return nearest ? shade(*nearest, nearest_x.dot(nearest->u_axis), nearest_x.dot(nearest->v_axis))
                   : 0.0;
  };
  for (int y = 0; y < h; ++y) {
    prepare(T_w_c_of_row(y));
    for (int x = 0; x < w; ++x) {
      double depth;
      const double value = cast(x, y, &depth);
      const size_t i = static_cast<size_t>(y) * w + x;
      f.gray[i] = static_cast<uint8_t>(std::clamp(std::lround(value * 255.0), 0L, 255L));
      const bool measured = depth < max_depth_m;
      f.depth[i] = measured ? static_cast<uint16_t>(std::lround(depth * depth_factor)) : 0;
    }
  }
  return f;
}

const std::vector<SyntheticFrame>& SyntheticScene::render_path(int frames, double fps) const {
  // Tests of one binary share the renders of one path.
  using Key = std::tuple<int, int, double, bool, bool, bool, bool, double, double, double, int>;
  static std::map<Key, std::vector<SyntheticFrame>> cache;
  std::vector<SyntheticFrame>& out =
      cache[Key(camera.width_px, frames, fps, with_box, box_in_corner, with_room, diagonal_path,
                back_wall_z_m, max_depth_m, pan_peak_deg_s, static_cast<int>(layout))];
  while (static_cast<int>(out.size()) < frames) {
    out.push_back(render(camera_at(static_cast<double>(out.size()) / fps)));
  }
  return out;
}

}  // namespace rgbdtam::testing

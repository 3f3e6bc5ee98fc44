#include "rgbdtam/core/depth_registration.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdtam/core/assert.hpp"
#include "rgbdtam/core/lanes.hpp"

namespace rgbdtam {
namespace {
constexpr uint16_t kEmpty = 0xFFFF;  // the z-buffer's "nothing yet"; 0 (a hole) at the end
// A source pixel covering more target pixels than this across is not a surface (a corner
// grazing the target's image plane); it is left out rather than painted over the image.
constexpr float kMaxFootprintPx = 16.0f;
// ceil() for x > -1 (x < INT_MAX): the library's is a call where SSE2 has no rounding
// instruction, and this is every pixel's.
int ceil_above_minus_one(float x) {
  const int truncated = static_cast<int>(x);
  return truncated < x ? truncated + 1 : truncated;
}

// A point of the target's frame to its raw (distorted) pixel.
void project_distorted(const CameraModel& camera, const Vector3d& p, double* u, double* v) {
  double xd = 0, yd = 0;
  camera.distortion.distort(p.x() / p.z(), p.y() / p.z(), &xd, &yd);
  *u = camera.intrinsics.fx_px * xd + camera.intrinsics.cx_px;
  *v = camera.intrinsics.fy_px * yd + camera.intrinsics.cy_px;
}
}  // namespace

void DepthRegistration::init(const CameraModel& source, const CameraModel& target,
                             const SE3& T_target_source, double depth_factor) {
  RGBDTAM_ASSERT(source.intrinsics.width_px % kLanes == 0, "rows of whole lanes");
  target_ = target;
  source_width_ = source.intrinsics.width_px;
  source_height_ = source.intrinsics.height_px;
  factor_ = static_cast<float>(depth_factor);
  inverse_factor_ = static_cast<float>(1.0 / depth_factor);
  const Vector3d t = T_target_source.translation();
  for (int i = 0; i < 3; ++i) t_[i] = static_cast<float>(t[i]);
  const Matrix3d R = T_target_source.rotation();
  const size_t pixels = static_cast<size_t>(source_width_) * static_cast<size_t>(source_height_);
  for (auto* table : {&ray_x_, &ray_y_, &ray_z_, &half_width_, &half_height_}) {
    table->reset(new float[pixels]);
  }
  for (auto* row : {&u_, &v_, &z_}) row->reset(new float[static_cast<size_t>(source_width_)]);
  const PinholeIntrinsics& k = source.intrinsics;
  auto ray = [&](double x, double y) {
    double xn = 0, yn = 0;
    source.distortion.undistort((x - k.cx_px) / k.fx_px, (y - k.cy_px) / k.fy_px, &xn, &yn);
    return Vector3d(R * Vector3d(xn, yn, 1.0));
  };
  for (int y = 0; y < source_height_; ++y) {
    for (int x = 0; x < source_width_; ++x) {
      const Vector3d centre = ray(x, y);
      const size_t i =
          static_cast<size_t>(y) * static_cast<size_t>(source_width_) + static_cast<size_t>(x);
      ray_x_[i] = static_cast<float>(centre.x());
      ray_y_[i] = static_cast<float>(centre.y());
      ray_z_[i] = static_cast<float>(centre.z());
      // The pixel's square in the target, around its centre: as seen from far away, where the
      // cameras' baseline no longer matters (nearer, it changes the square by t_z / z, a
      // fraction of a percent). Its four corners bound it: lens distortion and the rotation
      // turn it, and the bound leaves no crack between neighbours.
      double u_centre = 0, v_centre = 0, half_u = 0, half_v = 0;
      project_distorted(target, centre, &u_centre, &v_centre);
      for (const double dy : {-0.5, 0.5}) {
        for (const double dx : {-0.5, 0.5}) {
          double u = 0, v = 0;
          project_distorted(target, ray(x + dx, y + dy), &u, &v);
          half_u = std::max(half_u, std::abs(u - u_centre));
          half_v = std::max(half_v, std::abs(v - v_centre));
        }
      }
      // A square too large is left out for good: an empty bound covers no pixel.
      const bool surface = 2 * half_u <= kMaxFootprintPx && 2 * half_v <= kMaxFootprintPx;
      half_width_[i] = surface ? static_cast<float>(half_u) : -1.0f;
      half_height_[i] = surface ? static_cast<float>(half_v) : -1.0f;
    }
  }
}

void DepthRegistration::move_row(const uint16_t* depth, int y) {
  const float fx = static_cast<float>(target_.intrinsics.fx_px);
  const float fy = static_cast<float>(target_.intrinsics.fy_px);
  const float cx = static_cast<float>(target_.intrinsics.cx_px);
  const float cy = static_cast<float>(target_.intrinsics.cy_px);
  const RadTanDistortion& d = target_.distortion;
  const float k1 = static_cast<float>(d.k1), k2 = static_cast<float>(d.k2);
  const float k3 = static_cast<float>(d.k3), p1 = static_cast<float>(d.p1);
  const float p2 = static_cast<float>(d.p2);
  const size_t base = static_cast<size_t>(y) * static_cast<size_t>(source_width_);
  const float* rx = ray_x_.get() + base;
  const float* ry = ray_y_.get() + base;
  const float* rz = ray_z_.get() + base;
  // Four pixels at a time in one SSE2 or NEON register (GCC and Clang lower the arithmetic to
  // either; widths are multiples of 8). No branch: a pixel without depth lands at the
  // translation, which apply() skips by its depth.
  for (int x = 0; x < source_width_; x += kLanes) {
    Lanes depth_m;
    for (int i = 0; i < kLanes; ++i) depth_m[i] = static_cast<float>(depth[x + i]);
    depth_m *= inverse_factor_;
    const Lanes px = depth_m * load_lanes(rx + x) + t_[0];
    const Lanes py = depth_m * load_lanes(ry + x) + t_[1];
    const Lanes pz = depth_m * load_lanes(rz + x) + t_[2];
    const Lanes inverse_z = 1.0f / pz;
    const Lanes xn = px * inverse_z, yn = py * inverse_z;
    const Lanes r2 = xn * xn + yn * yn;
    const Lanes radial = 1.0f + r2 * (k1 + r2 * (k2 + r2 * k3));
    const Lanes xd = xn * radial + 2.0f * p1 * xn * yn + p2 * (r2 + 2.0f * xn * xn);
    const Lanes yd = yn * radial + p1 * (r2 + 2.0f * yn * yn) + 2.0f * p2 * xn * yn;
    store_lanes(fx * xd + cx, u_.get() + x);
    store_lanes(fy * yd + cy, v_.get() + x);
    store_lanes(pz, z_.get() + x);
  }
}

void DepthRegistration::apply(const uint16_t* source, uint16_t* out) {
  const int width = target_.intrinsics.width_px, height = target_.intrinsics.height_px;
  std::fill(out, out + static_cast<size_t>(width) * static_cast<size_t>(height), kEmpty);
  for (int y = 0; y < source_height_; ++y) {
    const size_t base = static_cast<size_t>(y) * static_cast<size_t>(source_width_);
    const uint16_t* depth = source + base;
    move_row(depth, y);
    for (int x = 0; x < source_width_; ++x) {
      const float z_m = z_[x];
      if (depth[x] == 0 || !(z_m > 0.0f)) continue;
      const float half_u = half_width_[base + static_cast<size_t>(x)];
      const float half_v = half_height_[base + static_cast<size_t>(x)];
      const float u0 = u_[x] - half_u, u1 = u_[x] + half_u;
      const float v0 = v_[x] - half_v, v1 = v_[x] + half_v;
      // Not NaN, and inside the image.
      if (!(u1 > 0.0f && v1 > 0.0f && u0 < width && v0 < height)) continue;
      // The target pixels whose centres lie in [u0, u1) x [v0, v1).
      const int x0 = ceil_above_minus_one(std::max(u0, -0.5f));
      const int x1 = std::min(width, ceil_above_minus_one(u1));
      const int y0 = ceil_above_minus_one(std::max(v0, -0.5f));
      const int y1 = std::min(height, ceil_above_minus_one(v1));
      const float raw = std::min(z_m * factor_ + 0.5f, static_cast<float>(kEmpty - 1));
      const uint16_t value = static_cast<uint16_t>(raw);
      for (int ty = y0; ty < y1; ++ty) {
        uint16_t* row = out + static_cast<size_t>(ty) * static_cast<size_t>(width);
        for (int tx = x0; tx < x1; ++tx) row[tx] = std::min(row[tx], value);
      }
    }
  }
  std::replace(out, out + static_cast<size_t>(width) * static_cast<size_t>(height), kEmpty,
               uint16_t{0});
}

}  // namespace rgbdtam

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
// The square above is a surface facing the cameras. A surface at a slant is seen more or less
// obliquely from the two, and stretches from one view to the other by about
// baseline / depth x tan(slant): left at its facing size, neighbouring squares part, and the
// target pixels between them are cracks, in runs where the stretch keeps them apart. 15 % more
// covers a 5 cm baseline up to 70 degrees of slant at 1.2 m (a D435's 1.5 cm: nearly every
// slant); near surfaces widen by the same 7.5 % of a pixel over farther ones at their outlines.
constexpr double kSlantMargin = 1.15;
// x within [lowest, highest]; NaN becomes lowest.
Lanes clamp(Lanes x, float lowest, float highest) {
  const Lanes above = x > lowest ? x : lowest;
  return above < highest ? above : highest;
}
// ceil() for x > -1 (and far below INT_MAX): SSE2 has no rounding instruction, and GCC would
// call the library's for every lane.
IntLanes ceil_above_minus_one(Lanes x) {
  const IntLanes truncated = __builtin_convertvector(x, IntLanes);
  return truncated - (__builtin_convertvector(truncated, Lanes) < x);  // true is -1
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
  for (auto* row : {&x0_, &x1_, &y0_, &y1_, &raw_}) {
    row->reset(new int32_t[static_cast<size_t>(source_width_)]);
  }
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
      half_width_[i] = surface ? static_cast<float>(half_u * kSlantMargin) : -1.0f;
      half_height_[i] = surface ? static_cast<float>(half_v * kSlantMargin) : -1.0f;
    }
  }
}

void DepthRegistration::move_row(const uint16_t* depth, int y) {
  const float fx = static_cast<float>(target_.intrinsics.fx_px);
  const float fy = static_cast<float>(target_.intrinsics.fy_px);
  const float cx = static_cast<float>(target_.intrinsics.cx_px);
  const float cy = static_cast<float>(target_.intrinsics.cy_px);
  const float width = static_cast<float>(target_.intrinsics.width_px);
  const float height = static_cast<float>(target_.intrinsics.height_px);
  const RadTanDistortion& d = target_.distortion;
  const float k1 = static_cast<float>(d.k1), k2 = static_cast<float>(d.k2);
  const float k3 = static_cast<float>(d.k3), p1 = static_cast<float>(d.p1);
  const float p2 = static_cast<float>(d.p2);
  const size_t base = static_cast<size_t>(y) * static_cast<size_t>(source_width_);
  const float* rx = ray_x_.get() + base;
  const float* ry = ray_y_.get() + base;
  const float* rz = ray_z_.get() + base;
  const float* half_u = half_width_.get() + base;
  const float* half_v = half_height_.get() + base;
  // Members in locals: the stores (memcpy) may alias anything, members would be reloaded.
  const float inverse_factor = inverse_factor_, factor = factor_;
  const float tx = t_[0], ty = t_[1], tz = t_[2];
  int32_t *x0_row = x0_.get(), *x1_row = x1_.get(), *y0_row = y0_.get(), *y1_row = y1_.get();
  int32_t* raw_row = raw_.get();
  // Four pixels at a time in one SSE2 or NEON register (GCC and Clang lower the arithmetic to
  // either; widths are multiples of 8), up to the integer bounds the scatter paints: no branch.
  for (int x = 0; x < source_width_; x += kLanes) {
    Lanes depth_m;
    for (int i = 0; i < kLanes; ++i) depth_m[i] = static_cast<float>(depth[x + i]);
    const IntLanes measured = depth_m > 0.0f;
    depth_m *= inverse_factor;
    const Lanes px = depth_m * load_lanes(rx + x) + tx;
    const Lanes py = depth_m * load_lanes(ry + x) + ty;
    const Lanes pz = depth_m * load_lanes(rz + x) + tz;
    const Lanes inverse_z = 1.0f / pz;
    const Lanes xn = px * inverse_z, yn = py * inverse_z;
    const Lanes r2 = xn * xn + yn * yn;
    const Lanes radial = 1.0f + r2 * (k1 + r2 * (k2 + r2 * k3));
    const Lanes xd = xn * radial + 2.0f * p1 * xn * yn + p2 * (r2 + 2.0f * xn * xn);
    const Lanes yd = yn * radial + p1 * (r2 + 2.0f * yn * yn) + 2.0f * p2 * xn * yn;
    const Lanes u = fx * xd + cx, v = fy * yd + cy;
    const Lanes hu = load_lanes(half_u + x), hv = load_lanes(half_v + x);
    // The target pixels whose centres lie in [u - hu, u + hu) x [v - hv, v + hv), within the
    // image: clamped first, so that a square outside it (or NaN) bounds nothing.
    const IntLanes x0 = ceil_above_minus_one(clamp(u - hu, -0.5f, width));
    const IntLanes y0 = ceil_above_minus_one(clamp(v - hv, -0.5f, height));
    const IntLanes x1 = ceil_above_minus_one(clamp(u + hu, -0.5f, width));
    const IntLanes y1 = ceil_above_minus_one(clamp(v + hv, -0.5f, height));
    // No depth, or behind the target: an empty bound.
    const IntLanes paints = measured & (pz > 0.0f);
    store_lanes(x0, x0_row + x);
    store_lanes(paints ? x1 : x0, x1_row + x);
    store_lanes(y0, y0_row + x);
    store_lanes(y1, y1_row + x);
    const Lanes raw = clamp(pz * factor + 0.5f, 0.0f, static_cast<float>(kEmpty - 1));
    store_lanes(__builtin_convertvector(raw, IntLanes), raw_row + x);
  }
}

void DepthRegistration::apply(const uint16_t* source, uint16_t* out) {
  const int width = target_.intrinsics.width_px, height = target_.intrinsics.height_px;
  std::fill(out, out + static_cast<size_t>(width) * static_cast<size_t>(height), kEmpty);
  const int32_t *x0_row = x0_.get(), *x1_row = x1_.get(), *y0_row = y0_.get();
  const int32_t *y1_row = y1_.get(), *raw_row = raw_.get();
  for (int y = 0; y < source_height_; ++y) {
    move_row(source + static_cast<size_t>(y) * static_cast<size_t>(source_width_), y);
    for (int x = 0; x < source_width_; ++x) {
      const int x0 = x0_row[x], x1 = x1_row[x];
      if (x0 >= x1) continue;
      const uint16_t value = static_cast<uint16_t>(raw_row[x]);
      for (int ty = y0_row[x], y1 = y1_row[x]; ty < y1; ++ty) {
        uint16_t* row = out + static_cast<size_t>(ty) * static_cast<size_t>(width);
        for (int tx = x0; tx < x1; ++tx) row[tx] = std::min(row[tx], value);
      }
    }
  }
  std::replace(out, out + static_cast<size_t>(width) * static_cast<size_t>(height), kEmpty,
               uint16_t{0});
}

}  // namespace rgbdtam

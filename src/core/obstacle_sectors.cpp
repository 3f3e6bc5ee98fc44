#include "rgbdtam/core/obstacle_sectors.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdtam {
namespace {
constexpr double kDegPerRad = 180.0 / M_PI;

// Bearing (deg, clockwise from forward) of a body-frame direction.
double bearing_deg(const Eigen::Vector3f& d) { return std::atan2(d.y(), d.x()) * kDegPerRad; }
}  // namespace

void ObstacleSectorizer::init(const PinholeIntrinsics& camera, const SE3& T_b_c,
                              double depth_factor, const DepthRange& range,
                              const ObstacleOptions& options) {
  camera_ = camera;
  R_b_c_ = T_b_c.rotation().cast<float>();
  t_b_c_ = T_b_c.translation().cast<float>();
  metres_per_unit_ = static_cast<float>(1.0 / depth_factor);
  min_m_ = static_cast<float>(range.min_m);
  max_m_ = static_cast<float>(range.max_m);
  lowest_m_ = static_cast<float>(options.lowest_m);
  highest_m_ = static_cast<float>(options.highest_m);
  stride_ = std::max(1, options.stride_px);
  fov_deg_ = options.fov_deg > 0
                 ? options.fov_deg
                 : 2.0 * std::atan(0.5 * camera.width_px / camera.fx_px) * kDegPerRad;
}

void ObstacleSectorizer::measure(const uint16_t* depth, ObstacleSectors* out) const {
  constexpr int n = ObstacleSectors::kCount;
  const float increment = static_cast<float>(fov_deg_ / n);
  // The sectors are centred on the optical axis's bearing.
  const float first =
      static_cast<float>(bearing_deg(R_b_c_ * Eigen::Vector3f::UnitZ()) - 0.5 * fov_deg_);
  float nearest[n];
  bool seen[n];
  std::fill(nearest, nearest + n, INFINITY);
  std::fill(seen, seen + n, false);
  const float fx = static_cast<float>(camera_.fx_px), fy = static_cast<float>(camera_.fy_px);
  const float cx = static_cast<float>(camera_.cx_px), cy = static_cast<float>(camera_.cy_px);
  for (int v = stride_ / 2; v < camera_.height_px; v += stride_) {
    const uint16_t* row = depth + static_cast<size_t>(v) * camera_.width_px;
    for (int u = stride_ / 2; u < camera_.width_px; u += stride_) {
      const float z = row[u] * metres_per_unit_;
      // No depth (0), or beyond the sensor's range. A reading nearer than its minimum is not
      // to be trusted for distance, but something is there: an obstacle at the minimum.
      if (z <= 0.f || z > max_m_) continue;
      const Eigen::Vector3f p =
          R_b_c_ * Eigen::Vector3f((u - cx) * z / fx, (v - cy) * z / fy, z) + t_b_c_;
      const int s =
          static_cast<int>(std::floor((static_cast<float>(bearing_deg(p)) - first) / increment));
      if (s < 0 || s >= n) continue;
      seen[s] = true;
      const float height = -p.z();
      if (height < lowest_m_ || height > highest_m_) continue;
      nearest[s] = std::min(nearest[s], z < min_m_ ? min_m_ : std::hypot(p.x(), p.y()));
    }
  }
  out->increment_deg = increment;
  out->angle_offset_deg = first + 0.5f * increment;
  out->min_cm = static_cast<uint16_t>(std::lround(min_m_ * 100));
  out->max_cm = static_cast<uint16_t>(std::min(std::lround(max_m_ * 100), 65000L));
  for (int s = 0; s < n; ++s) {
    if (std::isfinite(nearest[s])) {
      const long cm = std::lround(nearest[s] * 100);
      out->distance_cm[s] = static_cast<uint16_t>(std::clamp<long>(cm, out->min_cm, out->max_cm));
    } else {
      out->distance_cm[s] =
          seen[s] ? static_cast<uint16_t>(out->max_cm + 1) : ObstacleSectors::kUnknown;
    }
  }
}

void BlindedSectors::mark(double dt_s, ObstacleSectors* sectors) {
  const double reach_cm = 100.0 * max_speed_m_s_ * std::max(0.0, dt_s);
  for (int s = 0; s < ObstacleSectors::kCount; ++s) {
    uint16_t& d = sectors->distance_cm[s];
    const uint16_t last = last_cm_[s];
    const bool was_near =
        last != 0 && last != ObstacleSectors::kUnknown && last <= sectors->min_cm + reach_cm;
    if (d == ObstacleSectors::kUnknown && was_near) d = sectors->min_cm;
    last_cm_[s] = d;
  }
}

void BlindedSectors::forget() { std::fill(last_cm_, last_cm_ + ObstacleSectors::kCount, 0); }

}  // namespace rgbdtam

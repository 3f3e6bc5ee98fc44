#include "rgbdtam/core/multiview.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdtam/core/assert.hpp"

namespace rgbdtam {
namespace {
constexpr int kPatchSamples = 7;       // 1-D patch along the epipolar line (code)
constexpr int kPatchSpacingSteps = 2;  // 2 px between patch samples, in 1 px scan steps
constexpr float kPatchSpacingPx = kPatchSpacingSteps;
constexpr int kPatchReachSteps = kPatchSamples / 2 * kPatchSpacingSteps;  // centre to last sample
constexpr int kScanMarginSteps = 5;  // 2 steps each side for the parabola, and the ceil
constexpr int kMaxScanSteps = 256;
constexpr float kInfiniteCost = 1e30f;
constexpr float kIntervalSigmas = 4.f;  // a seed's search interval after an observation

struct Epipolar {
  Eigen::Vector3f a;  // R d: the ray of the keyframe pixel in the current frame
  Eigen::Vector3f t;  // translation of T_c_k
  Pinhole pinhole;
  // Projection of the keyframe pixel at inverse depth rho: pi(R d / rho + t) = pi(R d + rho t).
  bool project(float rho, Eigen::Vector2f* u) const {
    const Eigen::Vector3f h = a + rho * t;
    if (h.z() < 1e-3f) return false;
    pinhole.project(h.x(), h.y(), h.z(), &u->x(), &u->y());
    return true;
  }
  // The inverse depth whose projection is u, solved on the image axis the line moves along most.
  float inverse_depth_at(const Eigen::Vector2f& u, bool along_x) const {
    const float m = along_x ? (u.x() - pinhole.cx) / pinhole.fx : (u.y() - pinhole.cy) / pinhole.fy;
    const float num = (along_x ? a.x() : a.y()) - m * a.z();
    const float den = m * t.z() - (along_x ? t.x() : t.y());
    return std::fabs(den) < 1e-9f ? -1.f : num / den;
  }
};

// The scan steps i in [0, steps) whose patch centre u0 + (i - 2) d lies inside the image by
// margin: [*first, *last], solved per axis (the centres move along a line).
bool steps_inside(const ImageF& img, const Eigen::Vector2f& u0, const Eigen::Vector2f& d,
                  float margin, int steps, int* first, int* last) {
  float t_min = -2.f, t_max = static_cast<float>(steps) - 3.f;  // t = i - 2
  const float hi[2] = {img.width() - 1 - margin, img.height() - 1 - margin};
  for (int a = 0; a < 2; ++a) {
    if (std::fabs(d[a]) < 1e-9f) {
      if (u0[a] < margin || u0[a] > hi[a]) return false;
      continue;
    }
    const float t0 = (margin - u0[a]) / d[a], t1 = (hi[a] - u0[a]) / d[a];
    t_min = std::max(t_min, std::min(t0, t1));
    t_max = std::min(t_max, std::max(t0, t1));
  }
  if (t_min > t_max) return false;
  *first = static_cast<int>(std::ceil(t_min)) + 2;
  *last = static_cast<int>(std::floor(t_max)) + 2;
  return *first <= *last;
}

float sample(const ImageF& img, const Eigen::Vector2f& p) {
  return sample_bilinear(img, p.x(), p.y());
}
}  // namespace

size_t SeedMap::bytes_needed(const MultiViewOptions& opt) {
  return static_cast<size_t>(opt.max_seeds) *
         (sizeof(Seed) + static_cast<size_t>(opt.max_observations) * sizeof(Observation));
}

void SeedMap::allocate(const PinholeIntrinsics& k, const MultiViewOptions& opt) {
  RGBDTAM_ASSERT(std::ceil(opt.max_search_px) + kScanMarginSteps <= kMaxScanSteps,
                 "max_search_px exceeds the epipolar scan buffer");
  opt_ = opt;
  k_ = k;
  seeds_.reserve_once(opt.max_seeds);
  observations_.reserve_once(opt.max_seeds * opt.max_observations);
}

void SeedMap::reset(const ImageF& gray, const ImageF& sensor_inverse_depth, const ImageU8& edges,
                    const SE3& T_w_k, float max_inverse_depth) {
  gray_ = &gray;
  T_w_k_ = T_w_k;
  seeds_.clear();
  observations_.clear();
  const int w = gray.width(), h = gray.height(), b = opt_.border_px;
  auto gradient = [&](int x, int y, float* gx, float* gy) {
    *gx = 0.5f * (gray.at(x + 1, y) - gray.at(x - 1, y));
    *gy = 0.5f * (gray.at(x, y + 1) - gray.at(x, y - 1));
    return std::fabs(*gx) + std::fabs(*gy) >= opt_.min_gradient;
  };
  int64_t count = 0;
  float gx, gy;
  for (int y = b; y < h - b; ++y)
    for (int x = b; x < w - b; ++x) count += edges.at(x, y) != 0 && gradient(x, y, &gx, &gy);
  // Thin evenly, in raster order, down to the seed budget.
  const int64_t cap = opt_.max_seeds;
  int64_t index = 0;
  for (int y = b; y < h - b; ++y) {
    for (int x = b; x < w - b; ++x) {
      if (edges.at(x, y) == 0 || !gradient(x, y, &gx, &gy)) continue;
      const int64_t i = index++;
      if (count > cap && (i + 1) * cap / count == i * cap / count) continue;
      const float norm = std::sqrt(gx * gx + gy * gy);
      Seed s;
      s.x = static_cast<int16_t>(x);
      s.y = static_cast<int16_t>(y);
      s.gx = gx / norm;
      s.gy = gy / norm;
      s.sensor_rho = sensor_inverse_depth.at(x, y);
      s.rho_lo = opt_.min_inverse_depth;
      s.rho_hi = max_inverse_depth;
      s.count = 0;
      if (!seeds_.push_back(s)) return;
    }
  }
  for (int i = 0; i < seeds_.size() * opt_.max_observations; ++i)
    (void)observations_.push_back({0, 0});
}

SeedMap::Motion SeedMap::motion_to(const SE3& T_w_c) const {
  const SE3 T_c_k = T_w_c.inverse() * T_w_k_;
  return {T_c_k.rotation().cast<float>(), T_c_k.translation().cast<float>(),
          -(T_c_k.rotation().transpose() * T_c_k.translation()).cast<float>()};
}

bool SeedMap::search(const Seed& s, const ImageF& cur, const Motion& m, Observation* out) const {
  Epipolar e;
  e.pinhole = k_.pinhole();
  Eigen::Vector3f d(0.f, 0.f, 1.f);
  e.pinhole.back_project(s.x, s.y, 1.f, &d.x(), &d.y());
  e.a = m.R_c_k * d;
  e.t = m.t_c_k;
  Eigen::Vector2f u_far, u_near;
  if (!e.project(s.rho_lo, &u_far) || !e.project(s.rho_hi, &u_near)) return false;
  const Eigen::Vector2f segment = u_near - u_far;
  const float length = segment.norm();
  if (length > opt_.max_search_px || length < 1e-3f) return false;
  const Eigen::Vector2f dir_c = segment / length;
  // The epipolar direction in the keyframe: how the pixel moves towards the current camera.
  const float rho_mid = 0.5f * (s.rho_lo + s.rho_hi);
  const Eigen::Vector3f p = d / rho_mid;
  const Eigen::Vector3f towards = m.centre_k - p;
  Eigen::Vector2f dir_k(e.pinhole.fx * (towards.x() - p.x() / p.z() * towards.z()) / p.z(),
                        e.pinhole.fy * (towards.y() - p.y() / p.z() * towards.z()) / p.z());
  if (dir_k.norm() < 1e-6f) return false;
  dir_k.normalize();
  // Orient it like the current frame's scan direction, or the two patches would be mirrored:
  // a keyframe pixel one step along dir_k, at the same depth, must move along +dir_c.
  Eigen::Vector2f at_mid, shifted;
  Eigen::Vector3f d_step(0.f, 0.f, 1.f);
  e.pinhole.back_project(s.x + dir_k.x(), s.y + dir_k.y(), 1.f, &d_step.x(), &d_step.y());
  Epipolar stepped = e;
  stepped.a = m.R_c_k * d_step;
  if (!e.project(rho_mid, &at_mid) || !stepped.project(rho_mid, &shifted)) return false;
  if ((shifted - at_mid).dot(dir_c) < 0.f) dir_k = -dir_k;
  // The patch must cross the edge, not run along it.
  if (std::fabs(s.gx * dir_k.x() + s.gy * dir_k.y()) < opt_.min_alignment) return false;
  float ref[kPatchSamples];
  const Eigen::Vector2f origin(s.x, s.y);
  for (int j = 0; j < kPatchSamples; ++j) {
    ref[j] = 255.f * sample(*gray_, origin + (j - kPatchSamples / 2) * kPatchSpacingPx * dir_k);
  }
  // Scan the segment (plus 2 px each side, for the parabola) in 1 px steps. The patch's samples
  // are two steps apart, so every sample of every step lies on the line at a whole step from
  // u_far: the line is sampled once and each step's cost reads seven of those samples.
  const int steps = static_cast<int>(std::ceil(length)) + kScanMarginSteps;
  const float margin = 1.f + kPatchReachSteps;
  int first, last;
  if (!steps_inside(cur, u_far, dir_c, margin, steps, &first, &last)) return false;
  const int scored = last - first + 1;
  float line[kMaxScanSteps + 2 * kPatchReachSteps];
  const int line_start = first - 2 - kPatchReachSteps;  // in steps from u_far
  for (int k = 0; k < scored + 2 * kPatchReachSteps; ++k) {
    line[k] = 255.f * sample(cur, u_far + static_cast<float>(line_start + k) * dir_c);
  }
  float costs[kMaxScanSteps];
  std::fill(costs, costs + scored, 0.f);
  for (int j = 0; j < kPatchSamples; ++j) {
    const float r = ref[j];
    const float* at = line + j * kPatchSpacingSteps;
    for (int i = 0; i < scored; ++i) costs[i] += std::fabs(r - at[i]);
  }
  float best_cost = kInfiniteCost, prev = kInfiniteCost, before_best = kInfiniteCost;
  float after_best = kInfiniteCost;
  int best = -1;
  for (int i = 0; i < steps; ++i) {
    const float cost = i >= first && i <= last ? costs[i - first] : kInfiniteCost;
    if (i == best + 1) after_best = cost;
    if (cost < best_cost) {
      best_cost = cost;
      best = i;
      before_best = prev;
      after_best = kInfiniteCost;
    }
    prev = cost;
  }
  if (best < 0 || best_cost / kPatchSamples > opt_.max_mean_sad) return false;
  float offset = 0.f;
  if (before_best < kInfiniteCost && after_best < kInfiniteCost) {
    const float curvature = before_best - 2.f * best_cost + after_best;
    if (curvature > 1e-6f)
      offset = std::clamp(0.5f * (before_best - after_best) / curvature, -0.5f, 0.5f);
  }
  const Eigen::Vector2f match = u_far + (static_cast<float>(best) - 2.f + offset) * dir_c;
  const bool along_x = std::fabs(dir_c.x()) >= std::fabs(dir_c.y());
  const float rho = e.inverse_depth_at(match, along_x);
  const float rho_next = e.inverse_depth_at(match + dir_c, along_x);
  if (rho <= 0.f || rho_next <= 0.f) return false;
  const float sigma = std::fabs(rho_next - rho);  // one pixel of disparity
  const float parallax = e.t.norm() * rho;
  if (parallax < opt_.min_parallax || rho < s.rho_lo - sigma || rho > s.rho_hi + sigma)
    return false;
  out->rho = rho;
  out->sigma = std::max(sigma, 1e-6f);
  return true;
}

int SeedMap::observe(const ImageF& gray, const SE3& T_w_c) {
  const Motion motion = motion_to(T_w_c);
  int accepted = 0;
  for (int i = 0; i < seeds_.size(); ++i) {
    Seed& s = seeds_[i];
    if (s.count >= opt_.max_observations) continue;
    Observation o;
    if (!search(s, gray, motion, &o)) continue;
    observations_[i * opt_.max_observations + s.count] = o;
    ++s.count;
    s.rho_lo = std::max(opt_.min_inverse_depth, o.rho - kIntervalSigmas * o.sigma);
    s.rho_hi = std::max(s.rho_lo, std::min(s.rho_hi, o.rho + kIntervalSigmas * o.sigma));
    ++accepted;
  }
  return accepted;
}

void SeedMap::fuse(float sigma_sensor, FixedVector<FusedPixel>* out) const {
  out->clear();
  for (int i = 0; i < seeds_.size(); ++i) {
    const Seed& s = seeds_[i];
    FusedPixel f{s.x, s.y, 0.f, 0.f, gray_->at(s.x, s.y), DepthSource::kNone};
    if (s.count >= opt_.min_observations) {
      const Observation* obs = &observations_[i * opt_.max_observations];
      float rhos[64];
      const int n = std::min<int>(s.count, 64);
      for (int j = 0; j < n; ++j) rhos[j] = obs[j].rho;
      std::nth_element(rhos, rhos + n / 2, rhos + n);
      const float median = rhos[n / 2];
      // Inverse-variance fusion (paper eq. 7) of the observations that agree with the median.
      double info = 0, weighted = 0;
      int agree = 0;
      for (int j = 0; j < n; ++j) {
        if (std::fabs(obs[j].rho - median) > opt_.consistency_sigmas * obs[j].sigma) continue;
        const double w = 1.0 / (static_cast<double>(obs[j].sigma) * obs[j].sigma);
        info += w;
        weighted += w * obs[j].rho;
        ++agree;
      }
      const float rho = static_cast<float>(weighted / info);
      const float sigma = static_cast<float>(1.0 / std::sqrt(info));
      if (agree >= opt_.min_observations && agree * 5 >= n * 3 &&
          sigma <= opt_.max_relative_sigma * rho) {
        f.rho = rho;
        f.sigma = sigma;
        f.source = DepthSource::kMultiView;
      }
    }
    if (s.sensor_rho > 0.f) {
      if (f.source == DepthSource::kMultiView &&
          std::fabs(f.rho - s.sensor_rho) <
              3.f * std::sqrt(f.sigma * f.sigma + sigma_sensor * sigma_sensor)) {
        const float w_mv = 1.f / (f.sigma * f.sigma), w_s = 1.f / (sigma_sensor * sigma_sensor);
        f.rho = (w_mv * f.rho + w_s * s.sensor_rho) / (w_mv + w_s);
        f.sigma = 1.f / std::sqrt(w_mv + w_s);
        f.source = DepthSource::kFused;
      } else {
        // No multi-view estimate, or one the sensor contradicts: the sensor's reading stands.
        f.rho = s.sensor_rho;
        f.sigma = sigma_sensor;
        f.source = DepthSource::kSensor;
      }
    }
    if (f.source != DepthSource::kNone && !out->push_back(f)) return;
  }
}

}  // namespace rgbdtam

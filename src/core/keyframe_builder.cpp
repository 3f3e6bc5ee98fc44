#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "rgbdtam/core/rolling_shutter.hpp"
#include "rgbdtam/core/tracker.hpp"

namespace rgbdtam {
namespace {
constexpr int kBorderPx = 2;
constexpr int kHistogramBins = 1024;

int photometric_cap(const TrackerOptions& opt, int level) {
  int cap = opt.photometric_points_finest;
  for (int l = 0; l < level; ++l) cap /= 3;
  return std::max(cap, 1);
}

int points_capacity(const TrackerOptions& opt, const PinholeIntrinsics& k, int level,
                    bool photometric) {
  const int w = k.width_px, h = k.height_px;
  if (photometric) {
    if (opt.residuals.photometric == PhotometricMode::kOff) return 0;
    return opt.residuals.photometric == PhotometricMode::kDense ? w * h
                                                                : photometric_cap(opt, level);
  }
  switch (opt.residuals.geometric == GeometricMode::kOff ? GeometricSampling::kSemiDense
                                                         : opt.residuals.sampling) {
    case GeometricSampling::kSemiDense:
      return opt.residuals.geometric == GeometricMode::kOff ? 0 : photometric_cap(opt, level);
    case GeometricSampling::kSubsampled: {
      const int s = opt.geometric_step[level];
      return ((w + s - 1) / s) * ((h + s - 1) / s);
    }
    case GeometricSampling::kDense:
      return w * h;
  }
  return 0;
}

// Selects evenly spread members when there are more candidates than the cap: deterministic,
// so replays are reproducible, and spatially uniform because candidates come in raster order.
bool keep_candidate(int64_t index, int64_t count, int64_t cap) {
  if (count <= cap) return true;
  return (index + 1) * cap / count != index * cap / count;
}

void fill_jacobian(const float a[3], float x, float y, float z, float J[6]) {
  J[0] = a[0];
  J[1] = a[1];
  J[2] = a[2];
  J[3] = y * a[2] - z * a[1];  // p x a: rotational part of a * [I, -[p]x]
  J[4] = z * a[0] - x * a[2];
  J[5] = x * a[1] - y * a[0];
}
}  // namespace

void KeyframeBuilder::allocate(const PinholeIntrinsics& finest, const TrackerOptions& opt) {
  opt_ = opt;
  canny_.allocate(finest.width_px, finest.height_px);
  PinholeIntrinsics k = finest;
  for (int l = 0; l < kPyramidLevels; ++l) {
    edges_[l].allocate(k.width_px, k.height_px);
    gx_[l].allocate(k.width_px, k.height_px);
    gy_[l].allocate(k.width_px, k.height_px);
    k = k.half();
  }
}

size_t KeyframeBuilder::keyframe_bytes(const PinholeIntrinsics& finest, const TrackerOptions& opt) {
  size_t bytes = sizeof(Keyframe);
  PinholeIntrinsics k = finest;
  for (int l = 0; l < kPyramidLevels; ++l) {
    bytes += 2 * TrackPoints::bytes(points_capacity(opt, k, l, true)) +
             TrackPoints::bytes(points_capacity(opt, k, l, false));
    k = k.half();
  }
  return bytes;
}

int KeyframeBuilder::most_points(const PinholeIntrinsics& finest, const TrackerOptions& opt) {
  int most = 0;
  PinholeIntrinsics k = finest;
  for (int l = 0; l < kPyramidLevels; ++l) {
    most = std::max({most, points_capacity(opt, k, l, true), points_capacity(opt, k, l, false)});
    k = k.half();
  }
  return most;
}

void KeyframeBuilder::allocate_keyframe(Keyframe* kf) const {
  PinholeIntrinsics k;
  k.width_px = edges_[0].width();
  k.height_px = edges_[0].height();
  for (int l = 0; l < kPyramidLevels; ++l) {
    for (auto& set : kf->photometric_sets) set[l].reserve_once(points_capacity(opt_, k, l, true));
    kf->geometric[l].reserve_once(points_capacity(opt_, k, l, false));
    k = k.half();
  }
}

bool KeyframeBuilder::is_semidense_pixel(int level, int x, int y) const {
  const float g = std::fabs(gx_[level].at(x, y)) + std::fabs(gy_[level].at(x, y));
  return edges_[level].at(x, y) != 0 && g >= gradient_threshold_[level];
}

void KeyframeBuilder::build(const FramePyramid& frame, uint32_t id, int64_t timestamp_ns,
                            const SE3& T_w_k, Keyframe* kf, const FramePyramid* photometric_depth) {
  kf->id = id;
  kf->timestamp_ns = timestamp_ns;
  kf->T_w_k = T_w_k;
  kf->T_k_kd = frame.T_c_d();
  kf->row_motion = frame.fixed_row_motions().colour;
  kf->active_photometric = 0;
  prepare(frame);
  for (int l = 0; l < kPyramidLevels; ++l) {
    select_photometric(frame, photometric_depth != nullptr ? *photometric_depth : frame, l,
                       &kf->photometric_sets[0][l]);
    select_geometric(frame, l, &kf->geometric[l]);
  }
}

void KeyframeBuilder::build_photometric(const FramePyramid& frame, const ImageU8& edges,
                                        TrackPoints* sets) {
  prepare(frame, &edges);
  for (int l = 0; l < kPyramidLevels; ++l) select_photometric(frame, frame, l, &sets[l]);
}

void KeyframeBuilder::prepare(const FramePyramid& frame, const ImageU8* edges) {
  if (edges != nullptr) {
    std::memcpy(edges_[0].data(), edges->data(), static_cast<size_t>(edges_[0].size()));
  } else {
    canny_.detect(frame.gray(0), opt_.canny_low, opt_.canny_high, &edges_[0]);
  }
  for (int l = 0; l < kPyramidLevels; ++l) {
    compute_gradients(frame.gray(l), &gx_[l], &gy_[l]);
    if (l > 0) {
      ImageU8& coarse = edges_[l];
      const ImageU8& fine = edges_[l - 1];
      for (int y = 0; y < coarse.height(); ++y) {
        for (int x = 0; x < coarse.width(); ++x) {
          coarse.at(x, y) = fine.at(2 * x, 2 * y) | fine.at(2 * x + 1, 2 * y) |
                            fine.at(2 * x, 2 * y + 1) | fine.at(2 * x + 1, 2 * y + 1);
        }
      }
    }
    // Threshold at the requested top fraction of the level's L1 gradient magnitudes.
    int histogram[kHistogramBins] = {0};
    constexpr float kMaxGradient = 1.0f;  // central differences of [0,1] images
    const int n = gx_[l].size();
    for (int i = 0; i < n; ++i) {
      const float g = std::fabs(gx_[l].data()[i]) + std::fabs(gy_[l].data()[i]);
      const int bin =
          std::min(kHistogramBins - 1, static_cast<int>(g / kMaxGradient * kHistogramBins));
      ++histogram[bin];
    }
    const int wanted = static_cast<int>(opt_.gradient_top_fraction * static_cast<float>(n));
    int above = 0, bin = kHistogramBins - 1;
    for (; bin > 0; --bin) {
      above += histogram[bin];
      if (above >= wanted) break;
    }
    gradient_threshold_[l] = static_cast<float>(bin) * kMaxGradient / kHistogramBins;
  }
}

void KeyframeBuilder::select_photometric(const FramePyramid& frame, const FramePyramid& depth,
                                         int level, TrackPoints* out) {
  out->clear();
  if (opt_.residuals.photometric == PhotometricMode::kOff) return;
  const bool dense = opt_.residuals.photometric == PhotometricMode::kDense;
  const ImageF& img = frame.gray(level);
  const ImageF& idepth = depth.inverse_depth(level);
  const PinholeIntrinsics& k = frame.intrinsics(level);
  const int w = img.width(), h = img.height();
  auto candidate = [&](int x, int y) {
    if (idepth.at(x, y) <= 0.f) return false;
    if (dense) return std::fabs(gx_[level].at(x, y)) + std::fabs(gy_[level].at(x, y)) > 1e-4f;
    return is_semidense_pixel(level, x, y);
  };
  int64_t count = 0;
  for (int y = kBorderPx; y < h - kBorderPx; ++y)
    for (int x = kBorderPx; x < w - kBorderPx; ++x) count += candidate(x, y) ? 1 : 0;
  const int64_t cap = out->capacity();
  int64_t index = 0;
  const Pinhole pinhole = k.pinhole();
  const float fx = pinhole.fx, fy = pinhole.fy;
  // A rolling shutter: each row's point moved into the middle row's camera; its Jacobian stays
  // the row's (the difference is second order).
  const RowMotion rows(frame.fixed_row_motions().colour, h);
  for (int y = kBorderPx; y < h - kBorderPx; ++y) {
    const float s = rows.from_middle(static_cast<float>(y));
    for (int x = kBorderPx; x < w - kBorderPx; ++x) {
      if (!candidate(x, y)) continue;
      if (!keep_candidate(index++, count, cap)) continue;
      TrackPoint p;
      p.z = 1.0f / idepth.at(x, y);
      pinhole.back_project(static_cast<float>(x), static_cast<float>(y), p.z, &p.x, &p.y);
      p.ref = img.at(x, y);
      const float gx = gx_[level].at(x, y), gy = gy_[level].at(x, y);
      const float iz = 1.0f / p.z;
      // r = I_cur(warp) - I_kf: the keyframe-side (inverse-compositional) Jacobian is -grad I_kf.
      const float a[3] = {-gx * fx * iz, -gy * fy * iz, (gx * fx * p.x + gy * fy * p.y) * iz * iz};
      fill_jacobian(a, p.x, p.y, p.z, p.J);
      rows.move(s, &p.x, &p.y, &p.z);
      if (!out->push_back(p)) return;
    }
  }
}

void KeyframeBuilder::select_geometric(const FramePyramid& frame, int level, TrackPoints* out) {
  out->clear();
  if (opt_.residuals.geometric == GeometricMode::kOff) return;
  const ImageF& idepth = frame.inverse_depth(level);
  const PinholeIntrinsics& k = frame.intrinsics(level);
  const int w = idepth.width(), h = idepth.height();
  const GeometricSampling sampling = opt_.residuals.sampling;
  const int step = sampling == GeometricSampling::kSubsampled ? opt_.geometric_step[level] : 1;
  // A point stands for the step x step patch around it; its depth gradient is the patch's
  // least-squares plane (radius half a step, at least one pixel). Central differences of two
  // single pixels would carry the sensor's noise into the Jacobian: on a plane moving along
  // itself the Jacobian's two parts cancel only with the plane's own gradient, and that noise
  // gives every direction information from thousands of points (a wall and a floor seemed to
  // fix motion along both, 74 times over, in rendered sensor noise).
  const int radius = std::max(1, step / 2);
  float norm = 0.f;
  for (int i = -radius; i <= radius; ++i) norm += static_cast<float>(i * i);
  norm *= static_cast<float>(2 * radius + 1);
  auto surface_gradient = [&](int x, int y, float* gx, float* gy) {
    const float rho = idepth.at(x, y);
    if (rho <= 0.f) return false;
    float sx = 0.f, sy = 0.f;
    for (int j = -radius; j <= radius; ++j) {
      for (int i = -radius; i <= radius; ++i) {
        // Every pixel of the patch on the point's surface: no hole, no depth edge.
        const float v = idepth.at(x + i, y + j);
        const float reach = static_cast<float>(std::max(std::abs(i), std::abs(j)));
        if (v <= 0.f || std::fabs(v - rho) > kMaxRelativeDepthSlope * rho * reach) return false;
        sx += static_cast<float>(i) * v;
        sy += static_cast<float>(j) * v;
      }
    }
    *gx = sx / norm;
    *gy = sy / norm;
    return true;
  };
  auto candidate = [&](int x, int y) {
    float gx, gy;
    if (!surface_gradient(x, y, &gx, &gy)) return false;
    return sampling != GeometricSampling::kSemiDense || is_semidense_pixel(level, x, y);
  };
  const int start = std::max(kBorderPx, step / 2);
  int64_t count = 0;
  for (int y = start; y < h - kBorderPx; y += step)
    for (int x = start; x < w - kBorderPx; x += step) count += candidate(x, y) ? 1 : 0;
  const int64_t cap = out->capacity();
  int64_t index = 0;
  const Pinhole pinhole = k.pinhole();
  const float fx = pinhole.fx, fy = pinhole.fy;
  const bool inverse = opt_.residuals.geometric == GeometricMode::kInverseDepth;
  const RowMotion rows(frame.fixed_row_motions().depth, h);  // as the photometric points'
  for (int y = start; y < h - kBorderPx; y += step) {
    const float s = rows.from_middle(static_cast<float>(y));
    for (int x = start; x < w - kBorderPx; x += step) {
      if (!candidate(x, y)) continue;
      if (!keep_candidate(index++, count, cap)) continue;
      TrackPoint p;
      const float rho = idepth.at(x, y);
      p.z = 1.0f / rho;
      pinhole.back_project(static_cast<float>(x), static_cast<float>(y), p.z, &p.x, &p.y);
      p.ref = rho;
      float gx = 0.f, gy = 0.f;
      (void)surface_gradient(x, y, &gx, &gy);
      const float slope = gx * fx * p.x + gy * fy * p.y;
      float a[3];
      if (inverse) {
        // r = 1/z(q) - rho_cur(pi(q)); keyframe side: grad of rho_kf(pi(p)) - 1/p_z, negated.
        a[0] = gx * fx * rho;
        a[1] = gy * fy * rho;
        a[2] = (1.0f - slope) * rho * rho;
      } else {
        // r = z(q) - D_cur(pi(q)), with grad D = -z^2 grad rho.
        a[0] = -gx * fx * p.z;
        a[1] = -gy * fy * p.z;
        a[2] = slope - 1.0f;
      }
      fill_jacobian(a, p.x, p.y, p.z, p.J);
      rows.move(s, &p.x, &p.y, &p.z);
      if (!out->push_back(p)) return;
    }
  }
}

}  // namespace rgbdtam

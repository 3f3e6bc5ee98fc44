#include "rgbdtam/core/camera.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace rgbdtam {

void RadTanDistortion::distort(double x, double y, double* xd, double* yd) const {
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  *xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  *yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
}

void RadTanDistortion::undistort(double xd, double yd, double* x, double* y) const {
  double ux = xd, uy = yd;
  for (int i = 0; i < 50; ++i) {
    double dx, dy;
    distort(ux, uy, &dx, &dy);
    const double ex = dx - xd, ey = dy - yd;
    ux -= ex;
    uy -= ey;
    if (ex * ex + ey * ey < 1e-24) break;
  }
  *x = ux;
  *y = uy;
}

void Undistorter::init(const PinholeIntrinsics& k, const RadTanDistortion& d) {
  width_ = k.width_px;
  height_ = k.height_px;
  identity_ = d.is_zero();
  if (identity_) return;
  const size_t n = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  tap_index_.reset(new int32_t[n]);
  for (auto& w : tap_weight_) w.reset(new uint16_t[n]);
  nearest_.reset(new int32_t[n]);
  for (int v = 0; v < height_; ++v) {
    for (int u = 0; u < width_; ++u) {
      const double x = (u - k.cx_px) / k.fx_px;
      const double y = (v - k.cy_px) / k.fy_px;
      double xd, yd;
      d.distort(x, y, &xd, &yd);
      const double su = k.fx_px * xd + k.cx_px;
      const double sv = k.fy_px * yd + k.cy_px;
      const size_t i = static_cast<size_t>(v) * width_ + u;
      const bool inside = su >= 0.0 && sv >= 0.0 && su < width_ - 1 && sv < height_ - 1;
      if (inside) {
        const int x0 = static_cast<int>(su), y0 = static_cast<int>(sv);
        const long ax = std::lround((su - x0) * kTapOne), ay = std::lround((sv - y0) * kTapOne);
        auto w = [](long a, long b) { return static_cast<uint16_t>(a * b / kTapOne); };
        tap_index_[i] = y0 * width_ + x0;
        tap_weight_[1][i] = w(ax, kTapOne - ay);
        tap_weight_[2][i] = w(kTapOne - ax, ay);
        tap_weight_[3][i] = w(ax, ay);
        // The four weights sum to exactly one.
        tap_weight_[0][i] = static_cast<uint16_t>(kTapOne - tap_weight_[1][i] - tap_weight_[2][i] -
                                                  tap_weight_[3][i]);
      } else {
        tap_index_[i] = 0;  // weights 0: the pixel becomes 0 without a branch
        for (auto& w : tap_weight_) w[i] = 0;
      }
      const long nu = std::lround(su), nv = std::lround(sv);
      nearest_[i] = (nu >= 0 && nv >= 0 && nu < width_ && nv < height_)
                        ? static_cast<int32_t>(nv * width_ + nu)
                        : -1;
    }
  }
}

void Undistorter::undistort_gray(const uint8_t* raw, ImageF* out) const {
  constexpr float kToUnit = 1.0f / 255.0f;
  float* dst = out->data();
  const int n = width_ * height_;
  if (identity_) {
    for (int i = 0; i < n; ++i) dst[i] = raw[i] * kToUnit;
    return;
  }
  // Fixed-point weights (in 1/16384), within 0.05 of a grey level; the weighted sums stay below
  // 2^24, so float computes them exactly. In chunks: the 2x2 source pixels of each output pixel
  // are copied (two bytes above, two below) in a scalar loop, SSE2 and NEON having no gather,
  // then weighed in one that vectorises.
  constexpr float kTapToUnit = kToUnit / kTapOne;
  constexpr int kChunk = 256;
  uint8_t above[2 * kChunk], below[2 * kChunk];
  for (int start = 0; start < n; start += kChunk) {
    const int m = std::min(kChunk, n - start);
    const int32_t* index = tap_index_.get() + start;
    for (int i = 0; i < m; ++i) {
      const uint8_t* p = raw + index[i];
      std::memcpy(above + 2 * i, p, 2);
      std::memcpy(below + 2 * i, p + width_, 2);
    }
    const uint16_t* w0 = tap_weight_[0].get() + start;
    const uint16_t* w1 = tap_weight_[1].get() + start;
    const uint16_t* w2 = tap_weight_[2].get() + start;
    const uint16_t* w3 = tap_weight_[3].get() + start;
    float* __restrict out_chunk = dst + start;
    for (int i = 0; i < m; ++i) {
      const float v =
          static_cast<float>(above[2 * i]) * w0[i] + static_cast<float>(above[2 * i + 1]) * w1[i] +
          static_cast<float>(below[2 * i]) * w2[i] + static_cast<float>(below[2 * i + 1]) * w3[i];
      out_chunk[i] = v * kTapToUnit;
    }
  }
}

void Undistorter::undistort_depth(const uint16_t* raw, const float* table, ImageF* out) const {
  float* dst = out->data();
  const int n = width_ * height_;
  if (identity_) {
    for (int i = 0; i < n; ++i) dst[i] = table[raw[i]];
    return;
  }
  for (int i = 0; i < n; ++i) dst[i] = table[nearest_[i] < 0 ? 0 : raw[nearest_[i]]];
}

}  // namespace rgbdtam

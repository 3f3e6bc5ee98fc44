#include "rgbdtam/core/pyramid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace rgbdtam {
namespace {
// Inverse depths in one 2x2 block are averaged only when they agree within this ratio;
// otherwise the block straddles a depth edge and is left invalid.
constexpr float kDepthBlockAgreement = 0.9f;

void downsample_gray(const ImageF& fine, ImageF* coarse) {
  for (int y = 0; y < coarse->height(); ++y) {
    const float* r0 = fine.row(2 * y);
    const float* r1 = fine.row(2 * y + 1);
    float* out = coarse->row(y);
    for (int x = 0; x < coarse->width(); ++x) {
      out[x] = 0.25f * (r0[2 * x] + r0[2 * x + 1] + r1[2 * x] + r1[2 * x + 1]);
    }
  }
}

// An inverse depth is 0 (none) or positive and finite, and such floats order as their bits do
// as integers. The row compares bits, so that it vectorises to integer min and max: float ones
// must keep NaN's semantics, which took NEON 126 instructions per four blocks instead of 50.
int32_t bits_of(float v) {
  int32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}

float float_of(int32_t bits) {
  float v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

// One row of 2x2 blocks, without branches: an invalid inverse depth adds nothing to the sum and
// is kept out of the minimum.
void downsample_inverse_depth_row(const float* __restrict r0, const float* __restrict r1,
                                  float* __restrict out, int width) {
  const int32_t none = bits_of(1e30f);
  for (int x = 0; x < width; ++x) {
    const float a = r0[2 * x], b = r0[2 * x + 1], c = r1[2 * x], d = r1[2 * x + 1];
    const int32_t ia = bits_of(a), ib = bits_of(b), ic = bits_of(c), id = bits_of(d);
    const float sum = ((a + b) + c) + d;
    const float lo = float_of(std::min(std::min(ia > 0 ? ia : none, ib > 0 ? ib : none),
                                       std::min(ic > 0 ? ic : none, id > 0 ? id : none)));
    const float hi = float_of(std::max(std::max(ia, ib), std::max(ic, id)));
    const int n = (ia > 0) + (ib > 0) + (ic > 0) + (id > 0);
    const float mean = sum / static_cast<float>(std::max(n, 1));
    out[x] = ((n >= 2) & (lo >= kDepthBlockAgreement * hi)) ? mean : 0.f;
  }
}

void downsample_inverse_depth(const ImageF& fine, ImageF* coarse) {
  for (int y = 0; y < coarse->height(); ++y) {
    downsample_inverse_depth_row(fine.row(2 * y), fine.row(2 * y + 1), coarse->row(y),
                                 coarse->width());
  }
}
}  // namespace

void FramePyramid::allocate(const PinholeIntrinsics& finest, double depth_factor,
                            const DepthRange& range) {
  constexpr int kRawValues = 1 << 16;
  inverse_of_raw_.reset(new float[kRawValues]);
  for (int raw = 0; raw < kRawValues; ++raw) {
    const double z = raw / depth_factor;
    inverse_of_raw_[raw] =
        (z >= range.min_m && z <= range.max_m) ? static_cast<float>(1.0 / z) : 0.f;
  }
  RGBDTAM_ASSERT(finest.width_px % (1 << (kPyramidLevels - 1)) == 0 &&
                     finest.height_px % (1 << (kPyramidLevels - 1)) == 0,
                 "image size must be divisible by 8 for a 4-level pyramid");
  k_[0] = finest;
  for (int l = 1; l < kPyramidLevels; ++l) k_[l] = k_[l - 1].half();
  for (int l = 0; l < kPyramidLevels; ++l) {
    gray_[l].allocate(k_[l].width_px, k_[l].height_px);
    inv_depth_[l].allocate(k_[l].width_px, k_[l].height_px);
  }
}

void FramePyramid::build_gray() {
  for (int l = 1; l < kPyramidLevels; ++l) downsample_gray(gray_[l - 1], &gray_[l]);
}

void FramePyramid::build_inverse_depth(const uint16_t* raw, const Undistorter& undistorter) {
  undistorter.undistort_depth(raw, inverse_of_raw_.get(), &inv_depth_[0]);
  build_inverse_depth_levels();
}

void FramePyramid::build_inverse_depth(const ImageU16& undistorted) {
  const float* table = inverse_of_raw_.get();
  float* dst = inv_depth_[0].data();
  for (int i = 0; i < undistorted.size(); ++i) dst[i] = table[undistorted.data()[i]];
  build_inverse_depth_levels();
}

void FramePyramid::build_inverse_depth_levels() {
  for (int l = 1; l < kPyramidLevels; ++l) {
    downsample_inverse_depth(inv_depth_[l - 1], &inv_depth_[l]);
  }
  has_depth_ = true;
}

void FramePyramid::clear_depth() {
  for (auto& img : inv_depth_) img.fill(0.f);
  has_depth_ = false;
  T_c_d_ = SE3();
}

namespace {
// Central differences; a difference whose two samples are not both `usable` is left at 0.
template <typename Usable>
void central_differences(const ImageF& img, ImageF* gx, ImageF* gy, Usable usable) {
  const int w = img.width(), h = img.height();
  gx->fill(0.f);
  gy->fill(0.f);
  for (int y = 1; y < h - 1; ++y) {
    const float* r = img.row(y);
    const float* up = img.row(y - 1);
    const float* down = img.row(y + 1);
    float* ox = gx->row(y);
    float* oy = gy->row(y);
    for (int x = 1; x < w - 1; ++x) {
      if (usable(r[x - 1], r[x + 1])) ox[x] = 0.5f * (r[x + 1] - r[x - 1]);
      if (usable(up[x], down[x])) oy[x] = 0.5f * (down[x] - up[x]);
    }
  }
}
}  // namespace

void compute_gradients(const ImageF& img, ImageF* gx, ImageF* gy) {
  central_differences(img, gx, gy, [](float, float) { return true; });
}

void compute_depth_gradients(const ImageF& inv_depth, ImageF* gx, ImageF* gy) {
  central_differences(inv_depth, gx, gy, [](float a, float b) { return a > 0.f && b > 0.f; });
}

SurfaceCount count_surface_pixels(const ImageF& inv_depth, int stride) {
  SurfaceCount c;
  for (int y = 1; y < inv_depth.height() - 1; y += stride) {
    const float* r = inv_depth.row(y);
    const float* up = inv_depth.row(y - 1);
    const float* down = inv_depth.row(y + 1);
    for (int x = 1; x < inv_depth.width() - 1; x += stride) {
      const float rho = r[x];
      if (rho <= 0.f) continue;
      ++c.valid;
      if (r[x - 1] <= 0.f || r[x + 1] <= 0.f || up[x] <= 0.f || down[x] <= 0.f) continue;
      const float limit = 2.f * kMaxRelativeDepthSlope * rho;  // central differences span 2 px
      c.on_surface +=
          std::fabs(r[x + 1] - r[x - 1]) <= limit && std::fabs(down[x] - up[x]) <= limit;
    }
  }
  return c;
}

}  // namespace rgbdtam

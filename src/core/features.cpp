#include "rgbdtam/core/features.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdtam/core/xorshift.hpp"

namespace rgbdtam {
namespace {
// The 16 pixels of the radius-3 Bresenham circle, clockwise from the top.
constexpr int kCircle[16][2] = {{0, -3}, {1, -3},  {2, -2},  {3, -1}, {3, 0},  {3, 1},
                                {2, 2},  {1, 3},   {0, 3},   {-1, 3}, {-2, 2}, {-3, 1},
                                {-3, 0}, {-3, -1}, {-2, -2}, {-1, -3}};
constexpr int kOrientationRadius = 15;
constexpr int kPatternRadius = 13;
constexpr int kBorder = kFeatureBorderPx;
static_assert(kBorder == kOrientationRadius + 1, "the border keeps the orientation patch inside");
constexpr int kGridColumns = 8, kGridRows = 6;

// Nine or more contiguous set bits of a 16-bit circular mask.
bool has_arc_of_nine(uint32_t mask) {
  uint32_t m = mask | (mask << 16);
  uint32_t run = m;
  for (int i = 1; i < 9; ++i) run &= m >> i;
  return run != 0;
}

void smooth_rows(const ImageF& in, ImageF* out) {
  const int w = in.width();
  for (int y = 0; y < in.height(); ++y) {
    const float* r = in.row(y);
    float* o = out->row(y);
    o[0] = r[0], o[1] = r[1], o[w - 2] = r[w - 2], o[w - 1] = r[w - 1];
    for (int x = 2; x < w - 2; ++x) {
      o[x] = (r[x - 2] + r[x + 2] + 4.f * (r[x - 1] + r[x + 1]) + 6.f * r[x]) * (1.f / 16.f);
    }
  }
}

void smooth_columns(const ImageF& in, ImageF* out) {
  const int w = in.width(), h = in.height();
  for (int y = 0; y < h; ++y) {
    float* o = out->row(y);
    if (y < 2 || y >= h - 2) {
      std::copy(in.row(y), in.row(y) + w, o);
      continue;
    }
    const float *a = in.row(y - 2), *b = in.row(y - 1), *c = in.row(y), *d = in.row(y + 1),
                *e = in.row(y + 2);
    for (int x = 0; x < w; ++x) {
      o[x] = (a[x] + e[x] + 4.f * (b[x] + d[x]) + 6.f * c[x]) * (1.f / 16.f);
    }
  }
}
}  // namespace

void FeatureExtractor::allocate(int width, int height, const FeatureOptions& opt) {
  RGBDTAM_ASSERT(width > 2 * kBorder && height > 2 * kBorder, "image too small for features");
  opt_ = opt;
  smooth_.allocate(width, height);
  tmp_.allocate(width, height);
  score_.allocate(width, height);
  // 3x3 non-maximum suppression leaves at most one corner per 2x2 block.
  candidates_.reserve_once(width * height / 4);
  for (int dy = 0; dy <= kOrientationRadius; ++dy) {
    circle_extent_[dy] = static_cast<int16_t>(std::floor(
        std::sqrt(static_cast<double>(kOrientationRadius * kOrientationRadius - dy * dy))));
  }
  // Test pairs drawn once, from a fixed seed, about an isotropic Gaussian (BRIEF's best
  // layout, sigma = patch / 5): a sum of four uniforms, kept inside the pattern's disc.
  uint32_t seed = 0x9E3779B9u;
  auto coordinate = [&]() {
    for (;;) {
      double s = 0.0;
      for (int i = 0; i < 4; ++i) s += static_cast<double>(xorshift32(&seed)) / 4294967295.0 - 0.5;
      const double v = s * (31.0 / 5.0) / std::sqrt(4.0 / 12.0);
      if (std::fabs(v) <= kPatternRadius) return v;
    }
  };
  double base[kTests][4];
  for (auto& t : base) {
    do {
      for (double& c : t) c = coordinate();
    } while (t[0] * t[0] + t[1] * t[1] > kPatternRadius * kPatternRadius ||
             t[2] * t[2] + t[3] * t[3] > kPatternRadius * kPatternRadius);
  }
  for (int b = 0; b < kAngleBins; ++b) {
    const double a = 2.0 * M_PI * b / kAngleBins, c = std::cos(a), s = std::sin(a);
    for (int i = 0; i < kTests; ++i) {
      auto turn = [&](double x, double y, int8_t* ox, int8_t* oy) {
        *ox = static_cast<int8_t>(std::lround(c * x - s * y));
        *oy = static_cast<int8_t>(std::lround(s * x + c * y));
      };
      turn(base[i][0], base[i][1], &pattern_[b][i].x1, &pattern_[b][i].y1);
      turn(base[i][2], base[i][3], &pattern_[b][i].x2, &pattern_[b][i].y2);
    }
  }
}

void FeatureExtractor::detect(const ImageF& gray) {
  const int w = gray.width(), h = gray.height();
  const float t = opt_.fast_threshold;
  int offset[16];
  for (int i = 0; i < 16; ++i) offset[i] = kCircle[i][1] * w + kCircle[i][0];
  score_.fill(0.f);
  for (int y = kBorder; y < h - kBorder; ++y) {
    const float* r = gray.row(y);
    float* s = score_.row(y);
    for (int x = kBorder; x < w - kBorder; ++x) {
      const float* p = r + x;
      const float hi = *p + t, lo = *p - t;
      // An arc of nine covers at least two of the four compass pixels.
      int bright = 0, dark = 0;
      for (int i = 0; i < 16; i += 4) {
        bright += p[offset[i]] > hi;
        dark += p[offset[i]] < lo;
      }
      if (bright < 2 && dark < 2) continue;
      uint32_t bright_mask = 0, dark_mask = 0;
      float bright_sum = 0.f, dark_sum = 0.f;
      for (int i = 0; i < 16; ++i) {
        const float v = p[offset[i]];
        if (v > hi) bright_mask |= 1u << i, bright_sum += v - hi;
        if (v < lo) dark_mask |= 1u << i, dark_sum += lo - v;
      }
      if (has_arc_of_nine(bright_mask)) s[x] = bright_sum;
      if (has_arc_of_nine(dark_mask)) s[x] = std::max(s[x], dark_sum);
    }
  }
}

float FeatureExtractor::orientation(const ImageF& gray, int x, int y) const {
  double m10 = 0.0, m01 = 0.0;
  for (int dy = -kOrientationRadius; dy <= kOrientationRadius; ++dy) {
    const int e = circle_extent_[std::abs(dy)];
    const float* r = gray.row(y + dy) + x;
    double row = 0.0;
    for (int dx = -e; dx <= e; ++dx) {
      m10 += dx * r[dx];
      row += r[dx];
    }
    m01 += dy * row;
  }
  return static_cast<float>(std::atan2(m01, m10));
}

void FeatureExtractor::describe(int x, int y, float angle_rad, Descriptor* d) const {
  int bin = static_cast<int>(std::lround(angle_rad * (kAngleBins / (2.0 * M_PI))));
  bin = ((bin % kAngleBins) + kAngleBins) % kAngleBins;
  *d = Descriptor();
  for (int i = 0; i < kTests; ++i) {
    const Test& t = pattern_[bin][i];
    if (smooth_.at(x + t.x1, y + t.y1) < smooth_.at(x + t.x2, y + t.y2)) {
      d->bits[i / 64] |= uint64_t{1} << (i % 64);
    }
  }
}

void FeatureExtractor::extract(const ImageF& gray, const ImageF& inverse_depth,
                               const PinholeIntrinsics& k, FixedVector<Feature>* out) {
  RGBDTAM_ASSERT(gray.width() == smooth_.width() && gray.height() == smooth_.height() &&
                     inverse_depth.width() == gray.width(),
                 "feature images differ from the allocated size");
  out->clear();
  detect(gray);
  const int w = gray.width(), h = gray.height();
  candidates_.clear();
  for (int y = kBorder; y < h - kBorder; ++y) {
    for (int x = kBorder; x < w - kBorder; ++x) {
      const float s = score_.at(x, y);
      if (s <= 0.f || inverse_depth.at(x, y) <= 0.f) continue;
      bool peak = true;
      for (int dy = -1; dy <= 1 && peak; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const float n = score_.at(x + dx, y + dy);
          // Ties go to the first in raster order, so that exactly one of equal neighbours stays.
          if (n > s || (n == s && (dy < 0 || (dy == 0 && dx < 0)))) {
            peak = false;
            break;
          }
        }
      }
      if (peak && !candidates_.push_back({s, static_cast<int16_t>(x), static_cast<int16_t>(y)})) {
        break;
      }
    }
  }
  // The strongest corners of every grid cell first, so that one textured corner of the view
  // cannot take them all; then the strongest of those overall.
  auto cell = [&](const Corner& c) {
    return (c.y * kGridRows / h) * kGridColumns + c.x * kGridColumns / w;
  };
  std::sort(candidates_.begin(), candidates_.end(), [&](const Corner& a, const Corner& b) {
    const int ca = cell(a), cb = cell(b);
    if (ca != cb) return ca < cb;
    if (a.score != b.score) return a.score > b.score;
    return a.y != b.y ? a.y < b.y : a.x < b.x;
  });
  const int per_cell = 2 * opt_.max_features / (kGridColumns * kGridRows) + 1;
  int kept = 0;
  for (int i = 0, run = 0; i < candidates_.size(); ++i) {
    run = (i > 0 && cell(candidates_[i]) == cell(candidates_[i - 1])) ? run + 1 : 0;
    if (run < per_cell) candidates_[kept++] = candidates_[i];
  }
  const int n = std::min(kept, std::min(opt_.max_features, out->capacity()));
  std::partial_sort(candidates_.begin(), candidates_.begin() + n, candidates_.begin() + kept,
                    [](const Corner& a, const Corner& b) {
                      if (a.score != b.score) return a.score > b.score;
                      return a.y != b.y ? a.y < b.y : a.x < b.x;
                    });
  smooth_rows(gray, &tmp_);
  smooth_columns(tmp_, &smooth_);
  for (int i = 0; i < n; ++i) {
    const Corner& c = candidates_[i];
    Feature f;
    describe(c.x, c.y, orientation(gray, c.x, c.y), &f.descriptor);
    f.u_px = c.x;
    f.v_px = c.y;
    f.z_m = 1.f / inverse_depth.at(c.x, c.y);
    k.pinhole().back_project(f.u_px, f.v_px, f.z_m, &f.x_m, &f.y_m);
    (void)out->push_back(f);
  }
}

int match_features(const FixedVector<Feature>& query, const FixedVector<Feature>& place,
                   PointPair* pairs, int max_pairs) {
  constexpr int kMaxDistance = 64;  // of 256 bits
  constexpr double kRatio = 0.8;
  int n = 0;
  for (const Feature& q : query) {
    if (n == max_pairs) break;
    int best = 257, second = 257;
    const Feature* match = nullptr;
    for (const Feature& p : place) {
      const int d = hamming(q.descriptor, p.descriptor);
      if (d < best) {
        second = best;
        best = d;
        match = &p;
      } else if (d < second) {
        second = d;
      }
    }
    if (match == nullptr || best > kMaxDistance || best > kRatio * second) continue;
    pairs[n].a = Vector3d(q.x_m, q.y_m, q.z_m);
    pairs[n].b = Vector3d(match->x_m, match->y_m, match->z_m);
    ++n;
  }
  return n;
}

}  // namespace rgbdtam

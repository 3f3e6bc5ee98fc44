#include "rgbdtam/core/canny.hpp"

#include <cmath>

namespace rgbdtam {

void CannyDetector::allocate(int width, int height) {
  magnitude_.allocate(width, height);
  sector_.allocate(width, height);
  stack_.reset(new int32_t[static_cast<size_t>(width) * height]);
}

int CannyDetector::detect(const ImageF& gray, float low, float high, ImageU8* edges) {
  const int w = gray.width(), h = gray.height();
  RGBDTAM_ASSERT(w == magnitude_.width() && h == magnitude_.height(), "canny size mismatch");
  magnitude_.fill(0.f);
  edges->fill(0);
  // tan(22.5 deg) and tan(67.5 deg) split the directions into four sectors.
  constexpr float kTan22 = 0.41421356f, kTan67 = 2.41421356f;
  for (int y = 1; y < h - 1; ++y) {
    const float* up = gray.row(y - 1);
    const float* r = gray.row(y);
    const float* down = gray.row(y + 1);
    float* mag = magnitude_.row(y);
    uint8_t* sec = sector_.row(y);
    for (int x = 1; x < w - 1; ++x) {
      const float gx = 255.f * ((up[x + 1] + 2.f * r[x + 1] + down[x + 1]) -
                                (up[x - 1] + 2.f * r[x - 1] + down[x - 1]));
      const float gy = 255.f * ((down[x - 1] + 2.f * down[x] + down[x + 1]) -
                                (up[x - 1] + 2.f * up[x] + up[x + 1]));
      mag[x] = std::sqrt(gx * gx + gy * gy);
      const float ax = std::fabs(gx), ay = std::fabs(gy);
      if (ay <= kTan22 * ax) {
        sec[x] = 0;
      } else if (ay >= kTan67 * ax) {
        sec[x] = 2;
      } else {
        sec[x] = (gx * gy > 0.f) ? 1 : 3;  // 1: down-right diagonal, 3: down-left
      }
    }
  }
  // Non-maximum suppression; 2 marks a strong seed, 1 a weak candidate.
  int top = 0;
  for (int y = 2; y < h - 2; ++y) {
    for (int x = 2; x < w - 2; ++x) {
      const float m = magnitude_.at(x, y);
      if (m < low) continue;
      int dx = 1, dy = 0;
      switch (sector_.at(x, y)) {
        case 0:
          dx = 1;
          dy = 0;
          break;
        case 1:
          dx = 1;
          dy = 1;
          break;
        case 2:
          dx = 0;
          dy = 1;
          break;
        default:
          dx = -1;
          dy = 1;
          break;
      }
      const float a = magnitude_.at(x + dx, y + dy), b = magnitude_.at(x - dx, y - dy);
      if (m > a && m >= b) {
        if (m >= high) {
          edges->at(x, y) = 2;
          stack_[top++] = y * w + x;
        } else {
          edges->at(x, y) = 1;
        }
      }
    }
  }
  // Hysteresis: weak candidates 8-connected to a strong edge become edges.
  uint8_t* e = edges->data();
  while (top > 0) {
    const int i = stack_[--top];
    static constexpr int kOffsetsX[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
    static constexpr int kOffsetsY[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
    for (int k = 0; k < 8; ++k) {
      const int j = i + kOffsetsY[k] * w + kOffsetsX[k];
      if (e[j] == 1) {
        e[j] = 2;
        stack_[top++] = j;
      }
    }
  }
  int count = 0;
  for (int i = 0; i < w * h; ++i) {
    e[i] = e[i] == 2 ? 1 : 0;
    count += e[i];
  }
  return count;
}

}  // namespace rgbdtam

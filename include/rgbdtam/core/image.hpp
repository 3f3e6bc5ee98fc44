#pragma once
// A 2-D image whose storage is allocated once, at init, and never resized.
// Pixel (x, y) has its centre at integer coordinates; x right, y down.

#include <cstdint>
#include <memory>

#include "rgbdtam/core/assert.hpp"

namespace rgbdtam {

template <typename T>
class Image {
 public:
  Image() = default;
  // Init-time only: the one place an image allocates.
  void allocate(int width, int height) {
    RGBDTAM_ASSERT(width > 0 && height > 0, "image size must be positive");
    width_ = width;
    height_ = height;
    data_.reset(new T[static_cast<size_t>(width) * static_cast<size_t>(height)]());
  }
  int width() const { return width_; }
  int height() const { return height_; }
  int size() const { return width_ * height_; }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  T* row(int y) { return data_.get() + static_cast<size_t>(y) * width_; }
  const T* row(int y) const { return data_.get() + static_cast<size_t>(y) * width_; }
  T& at(int x, int y) { return row(y)[x]; }
  const T& at(int x, int y) const { return row(y)[x]; }
  void fill(T value) {
    for (int i = 0; i < size(); ++i) data_[i] = value;
  }
  bool contains(float x, float y, float margin) const {
    return x >= margin && y >= margin && x <= width_ - 1 - margin && y <= height_ - 1 - margin;
  }

 private:
  std::unique_ptr<T[]> data_;
  int width_ = 0;
  int height_ = 0;
};

using ImageF = Image<float>;
using ImageU8 = Image<uint8_t>;
using ImageU16 = Image<uint16_t>;

// The value at fractions ax, ay (in [0, 1)) between four pixels c00, c01 (the row above) and
// c10, c11.
inline float bilinear(float c00, float c01, float c10, float c11, float ax, float ay) {
  const float top = c00 + ax * (c01 - c00);
  const float bottom = c10 + ax * (c11 - c10);
  return top + ay * (bottom - top);
}

// Bilinear sample; the caller guarantees 0 <= x < w-1 and 0 <= y < h-1.
inline float sample_bilinear(const ImageF& img, float x, float y) {
  const int x0 = static_cast<int>(x);
  const int y0 = static_cast<int>(y);
  const float* r0 = img.row(y0) + x0;
  const float* r1 = r0 + img.width();
  return bilinear(r0[0], r0[1], r1[0], r1[1], x - static_cast<float>(x0),
                  y - static_cast<float>(y0));
}

// Packed 8-bit RGB to grey with ITU-R BT.601 luma, rounded: the weights of the benchmark's grey
// images, so every colour source (PNG, Kinect, OpenNI2) gives the tracker the same grey.
inline void rgb_to_gray(const uint8_t* rgb, uint8_t* gray, int pixels) {
  for (int i = 0; i < pixels; ++i, rgb += 3) {
    gray[i] = static_cast<uint8_t>((299 * rgb[0] + 587 * rgb[1] + 114 * rgb[2] + 500) / 1000);
  }
}

}  // namespace rgbdtam

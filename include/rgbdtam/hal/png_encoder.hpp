#pragma once
// PNG encoding through libpng with no heap use after init: libpng and zlib allocate from a
// fixed arena reset before each image, and the file is built in a buffer sized at init.
// Fast deflate (level 1): the recorder must keep up with the sensor.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/hal/png_arena.hpp"

namespace rgbdtam {

class PngEncoder {
 public:
  void allocate(int max_width, int max_height);
  // The encoded file is data()[0, size()) until the next call.
  Status encode_gray8(const uint8_t* pixels, int width, int height);
  Status encode_gray16(const uint16_t* pixels, int width, int height);
  const uint8_t* data() const { return out_.get(); }
  size_t size() const { return size_; }

  // libpng's write hook; public only so the C callback can reach it.
  bool append(const uint8_t* bytes, size_t n);

 private:
  Status encode(const void* pixels, int width, int height, int bit_depth);
  PngArena arena_;
  std::unique_ptr<uint8_t[]> out_;
  size_t capacity_ = 0;
  size_t size_ = 0;
};

}  // namespace rgbdtam

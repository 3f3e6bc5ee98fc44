#pragma once
// PNG decoding through libpng with no heap use after init: libpng and zlib allocate from a
// fixed arena that is reset before each image, and rows go straight into the caller's image.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/hal/png_arena.hpp"

namespace rgbdtam {

class PngDecoder {
 public:
  // Arena for libpng's structs, zlib's inflate state and window, and one row buffer.
  void allocate(int max_width);
  // 8-bit grey (colour images are converted with ITU-R BT.601 weights).
  Status decode_gray8(const uint8_t* png, size_t size, int width, int height, uint8_t* out);
  // 16-bit single channel (depth).
  Status decode_gray16(const uint8_t* png, size_t size, int width, int height, uint16_t* out);

  size_t arena_high_water() const { return arena_.high_water(); }

 private:
  Status decode(const uint8_t* png, size_t size, int width, int height, int bit_depth, void* out);
  PngArena arena_;
  std::unique_ptr<uint8_t[]> row_;
  int max_width_ = 0;
};

}  // namespace rgbdtam

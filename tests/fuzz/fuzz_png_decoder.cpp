// libFuzzer target for PNG decoding through our arena (libpng and zlib inside it): any bytes,
// as grey or depth, at the size the first byte chooses, must decode or fail with a status,
// never crash, overrun or leave the arena.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rgbdtam/hal/png_decoder.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static rgbdtam::PngDecoder decoder;
  static bool allocated = false;
  constexpr int kMaxWidth = 640;
  if (!allocated) {
    decoder.allocate(kMaxWidth);
    allocated = true;
  }
  // The expected size: what a sequence's config says, which a hostile file need not match.
  static const int kSizes[][2] = {{1, 1}, {8, 6}, {64, 48}, {640, 480}};
  const int* wh = kSizes[data[0] % 4];
  static std::vector<uint16_t> out(640 * 480);
  const bool depth = (data[0] & 4) != 0;
  if (depth) {
    (void)decoder.decode_gray16(data + 1, size - 1, wh[0], wh[1], out.data());
  } else {
    (void)decoder.decode_gray8(data + 1, size - 1, wh[0], wh[1],
                               reinterpret_cast<uint8_t*>(out.data()));
  }
  return 0;
}

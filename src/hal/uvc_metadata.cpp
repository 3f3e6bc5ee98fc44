#include "rgbdtam/hal/uvc_metadata.hpp"

#include "rgbdtam/core/byte_io.hpp"

namespace rgbdtam {
namespace {
constexpr size_t kBlockPrefix = 10;  // arrival ns (8) and USB frame number (2)
constexpr uint8_t kHasPts = 0x04, kHasScr = 0x08;
constexpr uint32_t kIntelCaptureTiming = 0x80000001u;
constexpr uint32_t kFrameCounterValid = 0x1;

uint32_t le32(const uint8_t* p) { return ByteReader(p, 4).get<uint32_t>(); }

// The camera's own blocks after the standard header: the capture timing's frame counter.
void parse_vendor_blocks(const uint8_t* p, size_t bytes, UvcFrameMetadata* out) {
  while (bytes >= 8 && !out->has_frame_counter) {
    const uint32_t id = le32(p), size = le32(p + 4);
    if (size < 8 || size > bytes) return;
    if (id == kIntelCaptureTiming && size >= 20 && (le32(p + 12) & kFrameCounterValid) != 0) {
      out->has_frame_counter = true;
      out->frame_counter = le32(p + 16);
    }
    p += size;
    bytes -= size;
  }
}
}  // namespace

bool parse_uvc_metadata(const uint8_t* data, size_t bytes, UvcFrameMetadata* out) {
  *out = UvcFrameMetadata();
  size_t at = 0;
  while (at + kBlockPrefix + 2 <= bytes) {
    const uint8_t* header = data + at + kBlockPrefix;
    const size_t length = header[0];
    if (length < 2 || at + kBlockPrefix + length > bytes) break;
    const uint8_t flags = header[1];
    size_t standard = 2;
    if ((flags & kHasPts) != 0 && length >= standard + 4) {
      if (!out->has_pts) out->pts = le32(header + standard);
      out->has_pts = true;
      standard += 4;
    }
    if ((flags & kHasScr) != 0) standard += 6;
    if (length > standard) parse_vendor_blocks(header + standard, length - standard, out);
    at += kBlockPrefix + length;
  }
  return out->has_pts || out->has_frame_counter;
}

}  // namespace rgbdtam

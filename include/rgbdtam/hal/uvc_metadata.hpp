#pragma once
// What uvcvideo's metadata node says about one frame. Its buffers (V4L2_META_FMT_UVC, or
// V4L2_META_FMT_D4XX for RealSense D4xx) hold blocks of: the host's arrival time (u64 ns), the
// USB frame number (u16), then a copy of the UVC payload header: its length (u8), its flags
// (u8), the PTS (u32, the camera's clock at capture) when flag 0x04 is set, the SCR (6 bytes)
// when 0x08 is, and in D4XX the camera's own blocks ({u32 id, u32 size, ...}, little endian):
// Intel's capture timing block (id 0x80000001) holds the camera's frame counter. Layout per the
// kernel's metafmt-uvc and metafmt-d4xx documentation.

#include <cstddef>
#include <cstdint>

namespace rgbdtam {

struct UvcFrameMetadata {
  bool has_pts = false;
  uint32_t pts = 0;  // the camera's clock at capture
  bool has_frame_counter = false;
  uint32_t frame_counter = 0;  // the camera's count of the frames it captured
};

// The first block's PTS and the first frame counter found; false when no complete block holds
// either (a buffer cut short is read up to its last complete block).
bool parse_uvc_metadata(const uint8_t* data, size_t bytes, UvcFrameMetadata* out);

}  // namespace rgbdtam

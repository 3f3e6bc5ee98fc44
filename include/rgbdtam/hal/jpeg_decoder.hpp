#pragma once
// MJPEG frames (UVC colour cameras) to grey through libjpeg-turbo's libjpeg API: only the luma
// is decoded (JCS_GRAYSCALE skips the chroma), straight into the caller's image.
//
// No allocation per frame: the row pointers are made at open, and libjpeg's memory manager
// draws on an arena sized at open, through libjpeg's own porting interface for memory
// (jmemsys: jpeg_get_small/large and their frees, defined here, so that the static link takes
// them instead of libjpeg's malloc-based jmemnobs). Blocks are freed from the top of the arena:
// libjpeg frees each image's pool when the image is done, so the arena returns to the same top
// after every frame; tables it keeps for the next image stay below. A JPEG that would need more
// than the arena is a decode error, not an allocation. Other libjpeg users (none in the static
// firmware; OpenNI2's recorder in a dynamic build) keep malloc: an arena is found by comparing
// libjpeg's client_data with the open decoders' arenas (at most 8), never by dereferencing it.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

class JpegArena {
 public:
  void allocate(size_t capacity_bytes);
  void* get(size_t bytes);  // null when it does not fit
  void put(void* block);
  size_t used_bytes() const { return top_; }
  size_t peak_bytes() const { return peak_; }
  size_t capacity_bytes() const { return capacity_; }

 private:
  std::unique_ptr<uint8_t[]> memory_;
  uint8_t* base_ = nullptr;  // 16-byte aligned
  size_t capacity_ = 0, top_ = 0, peak_ = 0;
};

class JpegDecoder {
 public:
  JpegDecoder();
  ~JpegDecoder();
  JpegDecoder(const JpegDecoder&) = delete;
  JpegDecoder& operator=(const JpegDecoder&) = delete;
  // Init time: frames of width x height (a JPEG of another size is an error).
  Status open(int width, int height);
  // One JPEG to width x height grey; a corrupt or truncated JPEG is an error naming why.
  Status decode(const uint8_t* jpeg, size_t bytes, uint8_t* gray);
  const JpegArena& arena() const { return arena_; }
  uint32_t decoded() const { return decoded_; }

 private:
  struct State;
  std::unique_ptr<State> state_;
  JpegArena arena_;
  int width_ = 0, height_ = 0;
  uint32_t decoded_ = 0;
};

}  // namespace rgbdtam

#pragma once
// A fixed arena for libpng's and zlib's allocations, reset before each image, so that PNG
// decoding and encoding never use the heap after init.

#include <cstddef>
#include <cstdint>
#include <memory>

namespace rgbdtam {

class PngArena {
 public:
  void allocate(size_t bytes) {
    size_ = bytes;
    memory_.reset(new uint8_t[bytes]);
  }
  void reset() { used_ = 0; }
  // Null when full: libpng then reports out of memory.
  void* alloc(size_t n) {
    const size_t aligned = (n + 15) & ~static_cast<size_t>(15);
    if (size_ - used_ < aligned) return nullptr;
    void* p = memory_.get() + used_;
    used_ += aligned;
    if (used_ > high_water_) high_water_ = used_;
    return p;
  }
  size_t high_water() const { return high_water_; }

 private:
  std::unique_ptr<uint8_t[]> memory_;
  size_t size_ = 0;
  size_t used_ = 0;
  size_t high_water_ = 0;
};

}  // namespace rgbdtam

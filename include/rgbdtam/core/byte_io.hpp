#pragma once
// Little-endian fixed-width fields for the project's binary files (vocabulary, map), and the
// FNV-1a checksum they end with. The targets are little-endian, as the formats, so a field is
// its bytes. The reader never reads past its end: a short file reads as zeros and !ok().

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace rgbdtam {

constexpr uint32_t kFnv1aStart = 2166136261u;
inline uint32_t fnv1a(const uint8_t* data, size_t size, uint32_t h = kFnv1aStart) {
  for (size_t i = 0; i < size; ++i) h = (h ^ data[i]) * 16777619u;
  return h;
}

template <typename T>
void put_le(uint8_t** p, T v) {
  std::memcpy(*p, &v, sizeof(T));
  *p += sizeof(T);
}

class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : p_(data), end_(data + size) {}
  template <typename T>
  T get() {
    T v{};
    bytes(&v, sizeof(T));
    return v;
  }
  void bytes(void* out, size_t n) {
    if (static_cast<size_t>(end_ - p_) < n) {
      ok_ = false;
      std::memset(out, 0, n);
      p_ = end_;
      return;
    }
    std::memcpy(out, p_, n);
    p_ += n;
  }
  bool ok() const { return ok_; }
  size_t left() const { return static_cast<size_t>(end_ - p_); }
  const uint8_t* position() const { return p_; }

 private:
  const uint8_t* p_;
  const uint8_t* end_;
  bool ok_ = true;
};

}  // namespace rgbdtam

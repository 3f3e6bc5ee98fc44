#pragma once
// A keyframe's residual points as a structure of arrays: each field is one aligned float array,
// padded to whole SIMD blocks, so the tracker's per-point loops vectorise. Capacity is set once.

#include <cstdint>
#include <cstring>
#include <memory>
#include <utility>

#include "rgbdtam/core/assert.hpp"

namespace rgbdtam {

// One residual point of a keyframe, in the keyframe's camera frame.
struct TrackPoint {
  float x, y, z;  // m
  float ref;      // keyframe intensity [0,1], or keyframe inverse depth 1/m
  float J[6];     // d residual / d (v, omega) at the identity, keyframe side
};

class TrackPoints {
 public:
  // Loops may run to padded_size(): the padding holds finite values (zero until written).
  static constexpr int kBlock = 8;
  static constexpr int kAlignBytes = 64;

  void reserve_once(int capacity) {
    RGBDTAM_ASSERT(storage_ == nullptr, "TrackPoints capacity is set once");
    capacity_ = capacity;
    stride_ = round_up(capacity, kAlignBytes / static_cast<int>(sizeof(float)));
    const size_t floats = static_cast<size_t>(kFields) * stride_ + kAlignBytes / sizeof(float);
    storage_.reset(new float[floats]());
    const uintptr_t raw = reinterpret_cast<uintptr_t>(storage_.get());
    const uintptr_t aligned = (raw + kAlignBytes - 1) & ~static_cast<uintptr_t>(kAlignBytes - 1);
    base_ = storage_.get() + (aligned - raw) / sizeof(float);
  }
  [[nodiscard]] bool push_back(const TrackPoint& p) {
    if (size_ >= capacity_) return false;
    const int i = size_++;
    field(kX)[i] = p.x;
    field(kY)[i] = p.y;
    field(kZ)[i] = p.z;
    field(kRef)[i] = p.ref;
    for (int k = 0; k < 6; ++k) field(kJ0 + k)[i] = p.J[k];
    return true;
  }
  TrackPoint operator[](int i) const {
    TrackPoint p;
    p.x = x()[i];
    p.y = y()[i];
    p.z = z()[i];
    p.ref = ref()[i];
    for (int k = 0; k < 6; ++k) p.J[k] = J(k)[i];
    return p;
  }
  void clear() { size_ = 0; }
  // Two sets of the same capacity trade buffers (no copy, no allocation).
  void swap(TrackPoints& other) {
    RGBDTAM_ASSERT(capacity_ == other.capacity_, "TrackPoints swapped across capacities");
    storage_.swap(other.storage_);
    std::swap(base_, other.base_);
    std::swap(stride_, other.stride_);
    std::swap(size_, other.size_);
  }
  // Another set's points, padding included, into this one's buffer (no allocation).
  void copy_from(const TrackPoints& other) {
    RGBDTAM_ASSERT(capacity_ == other.capacity_, "TrackPoints copied across capacities");
    for (int f = 0; f < kFields; ++f) {
      std::memcpy(field(f), other.field(f),
                  sizeof(float) * static_cast<size_t>(other.padded_size()));
    }
    size_ = other.size_;
  }
  int size() const { return size_; }
  int padded_size() const { return round_up(size_, kBlock); }
  int capacity() const { return capacity_; }
  bool empty() const { return size_ == 0; }

  const float* x() const { return field(kX); }
  const float* y() const { return field(kY); }
  const float* z() const { return field(kZ); }
  const float* ref() const { return field(kRef); }
  const float* J(int k) const { return field(kJ0 + k); }

  static int round_up(int n, int block) { return (n + block - 1) / block * block; }
  static size_t bytes(int capacity) {
    return (static_cast<size_t>(kFields) * round_up(capacity, kAlignBytes / sizeof(float)) +
            kAlignBytes / sizeof(float)) *
           sizeof(float);
  }

 private:
  enum Field { kX, kY, kZ, kRef, kJ0, kFields = kJ0 + 6 };
  float* field(int f) { return base_ + static_cast<size_t>(f) * stride_; }
  const float* field(int f) const { return base_ + static_cast<size_t>(f) * stride_; }

  std::unique_ptr<float[]> storage_;
  float* base_ = nullptr;
  int capacity_ = 0, stride_ = 0, size_ = 0;
};

}  // namespace rgbdtam

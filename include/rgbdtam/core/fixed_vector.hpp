#pragma once
// A vector whose capacity is set once, at init. push_back never allocates: it reports a
// full vector by returning false, so the caller states its own overflow policy.

#include <memory>

#include "rgbdtam/core/assert.hpp"

namespace rgbdtam {

template <typename T>
class FixedVector {
 public:
  void reserve_once(int capacity) {
    RGBDTAM_ASSERT(data_ == nullptr, "FixedVector capacity is set once");
    data_.reset(new T[static_cast<size_t>(capacity)]());
    capacity_ = capacity;
  }
  [[nodiscard]] bool push_back(const T& v) {
    if (size_ >= capacity_) return false;
    data_[size_++] = v;
    return true;
  }
  void clear() { size_ = 0; }
  void truncate(int size) {
    RGBDTAM_ASSERT(size >= 0 && size <= size_, "FixedVector::truncate can only shrink");
    size_ = size;
  }
  int size() const { return size_; }
  int capacity() const { return capacity_; }
  bool empty() const { return size_ == 0; }
  T& operator[](int i) { return data_[i]; }
  const T& operator[](int i) const { return data_[i]; }
  T* begin() { return data_.get(); }
  T* end() { return data_.get() + size_; }
  const T* begin() const { return data_.get(); }
  const T* end() const { return data_.get() + size_; }

 private:
  std::unique_ptr<T[]> data_;
  int capacity_ = 0;
  int size_ = 0;
};

}  // namespace rgbdtam

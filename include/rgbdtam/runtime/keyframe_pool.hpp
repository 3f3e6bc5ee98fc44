#pragma once
// Fixed-capacity keyframe storage. Policy when full: recycle the oldest keyframe that is neither
// the current tracking reference nor being mapped, and count it; tracking never stops for a
// full pool. With a capacity of at least 3 such a keyframe always exists.

#include "rgbdtam/core/tracker.hpp"

namespace rgbdtam {

class KeyframePool {
 public:
  void allocate(int capacity, const KeyframeBuilder& builder, int map_points_per_keyframe);
  // Returns a slot for a new keyframe; never the one at `keep`.
  Keyframe* acquire(const Keyframe* keep);
  int size() const { return used_; }
  Keyframe& at(int i) { return slots_[i]; }
  const Keyframe& at(int i) const { return slots_[i]; }
  int capacity() const { return capacity_; }
  int recycled() const { return recycled_; }

 private:
  std::unique_ptr<Keyframe[]> slots_;
  std::unique_ptr<uint64_t[]> age_;  // creation order per slot
  int capacity_ = 0;
  int used_ = 0;
  int recycled_ = 0;
  uint64_t clock_ = 0;
};

}  // namespace rgbdtam

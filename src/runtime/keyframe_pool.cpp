#include "rgbdtam/runtime/keyframe_pool.hpp"

namespace rgbdtam {

void KeyframePool::allocate(int capacity, const KeyframeBuilder& builder,
                            int map_points_per_keyframe) {
  RGBDTAM_ASSERT(capacity >= 3,
                 "a keyframe pool needs the reference, the mapped one and a new one");
  capacity_ = capacity;
  slots_.reset(new Keyframe[static_cast<size_t>(capacity)]);
  age_.reset(new uint64_t[static_cast<size_t>(capacity)]());
  for (int i = 0; i < capacity; ++i) {
    builder.allocate_keyframe(&slots_[i]);
    slots_[i].map_points.reserve_once(map_points_per_keyframe);
  }
}

Keyframe* KeyframePool::acquire(const Keyframe* keep) {
  int slot;
  if (used_ < capacity_) {
    slot = used_++;
  } else {
    slot = -1;
    for (int i = 0; i < capacity_; ++i) {
      if (&slots_[i] == keep || slots_[i].being_mapped.load(std::memory_order_acquire)) continue;
      if (slot < 0 || age_[i] < age_[slot]) slot = i;
    }
    RGBDTAM_ASSERT(slot >= 0, "keyframe pool: every slot is referenced or being mapped");
    ++recycled_;
  }
  age_[slot] = ++clock_;
  return &slots_[slot];
}

}  // namespace rgbdtam

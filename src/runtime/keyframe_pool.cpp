#include "rgbdtam/runtime/keyframe_pool.hpp"

namespace rgbdtam {

void KeyframePool::allocate(int capacity, const KeyframeBuilder& builder,
                            int map_points_per_keyframe) {
  RGBDTAM_ASSERT(capacity >= 3,
                 "a keyframe pool needs the reference, the mapped one and a new one");
  capacity_ = capacity;
  const size_t n = static_cast<size_t>(capacity);
  slots_.reset(new Keyframe[n]);
  age_.reset(new uint64_t[n]());
  generation_.reset(new uint32_t[n]());
  pins_.reset(new std::atomic<int>[n]);
  map_published_.reset(new std::atomic<bool>[n]);
  for (int i = 0; i < capacity; ++i) {
    builder.allocate_keyframe(&slots_[i]);
    slots_[i].map_points.reserve_once(map_points_per_keyframe);
    pins_[i].store(0, std::memory_order_relaxed);
    map_published_[i].store(false, std::memory_order_relaxed);
  }
}

int KeyframePool::slot_of(const Keyframe* kf) const {
  const long slot = kf - slots_.get();
  RGBDTAM_ASSERT(slot >= 0 && slot < capacity_, "keyframe not from this pool");
  return static_cast<int>(slot);
}

Keyframe* KeyframePool::acquire(const Keyframe* keep) {
  int slot;
  if (used_ < capacity_) {
    slot = used_++;
  } else {
    slot = -1;
    for (int i = 0; i < capacity_; ++i) {
      if (&slots_[i] == keep || pins_[i].load(std::memory_order_acquire) > 0) continue;
      if (slot < 0 || age_[i] < age_[slot]) slot = i;
    }
    RGBDTAM_ASSERT(slot >= 0, "keyframe pool: every slot is referenced or pinned");
    ++recycled_;
  }
  age_[slot] = ++clock_;
  ++generation_[slot];
  map_published_[slot].store(false, std::memory_order_relaxed);
  return &slots_[slot];
}

KeyframeHandle KeyframePool::handle(const Keyframe* kf) const {
  const int slot = slot_of(kf);
  return {slot, generation_[slot]};
}

Keyframe* KeyframePool::get(const KeyframeHandle& h) {
  if (h.slot < 0 || h.slot >= capacity_ || generation_[h.slot] != h.generation) {
    stale_lookups_.fetch_add(1, std::memory_order_relaxed);
    return nullptr;
  }
  return &slots_[h.slot];
}

void KeyframePool::pin(const KeyframeHandle& h) {
  RGBDTAM_ASSERT(get(h) != nullptr, "pinning a recycled keyframe");
  pins_[h.slot].fetch_add(1, std::memory_order_acq_rel);
}

void KeyframePool::unpin(const KeyframeHandle& h) {
  RGBDTAM_ASSERT(pins_[h.slot].load(std::memory_order_relaxed) > 0, "unpinning an unpinned slot");
  pins_[h.slot].fetch_sub(1, std::memory_order_acq_rel);
}

bool KeyframePool::pinned(const Keyframe* kf) const {
  return pins_[slot_of(kf)].load(std::memory_order_acquire) > 0;
}

void KeyframePool::publish_map(const KeyframeHandle& h) {
  map_published_[h.slot].store(true, std::memory_order_release);
}

bool KeyframePool::adopt_map(Keyframe* kf) {
  if (!map_published_[slot_of(kf)].exchange(false, std::memory_order_acq_rel)) return false;
  kf->swap_photometric();
  return true;
}

}  // namespace rgbdtam

#pragma once
// The dense keyframes (the tracker's and mapper's points, images and maps) in a fixed pool,
// shared by the tracker and the mapper. A slot is named by a handle (slot, generation);
// recycling a slot bumps its generation, so a handle to an evicted keyframe reads as gone: that
// is the eviction notice. A pinned slot is never recycled: the tracker pins a keyframe it hands
// to the mapper, the mapper unpins it when its map is published.
// Threads: the tracker owns every keyframe's contents, except that the mapper writes a pinned
// keyframe's inactive photometric set and map points, then publishes them (publish_map); the
// tracker adopts them between frames (adopt_map). Only pins and published maps are shared.
// Policy when full: recycle the oldest unpinned keyframe other than the one to keep, and count
// it; tracking never stops for a full pool. With a capacity of at least 3 such a slot exists.

#include <atomic>
#include <memory>

#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/port/messages.hpp"

namespace rgbdtam {

class KeyframePool {
 public:
  void allocate(int capacity, const KeyframeBuilder& builder, int map_points_per_keyframe);
  // Tracker: a slot for a new keyframe; never the one at `keep`, never a pinned one.
  Keyframe* acquire(const Keyframe* keep);
  int size() const { return used_; }
  Keyframe& at(int i) { return slots_[i]; }
  const Keyframe& at(int i) const { return slots_[i]; }
  int capacity() const { return capacity_; }
  int recycled() const { return recycled_; }

  KeyframeHandle handle(const Keyframe* kf) const;
  // The keyframe a handle names, or null once its slot was recycled.
  Keyframe* get(const KeyframeHandle& h);
  // Lookups refused because the handle's slot had been recycled (any thread).
  uint32_t stale_lookups() const { return stale_lookups_.load(std::memory_order_relaxed); }
  void pin(const KeyframeHandle& h);
  void unpin(const KeyframeHandle& h);
  bool pinned(const Keyframe* kf) const;
  // Mapper: the keyframe's inactive set and map points hold its new map.
  void publish_map(const KeyframeHandle& h);
  // Tracker, between frames: swaps in a published map. True when there was one.
  bool adopt_map(Keyframe* kf);

 private:
  int slot_of(const Keyframe* kf) const;

  std::unique_ptr<Keyframe[]> slots_;
  std::unique_ptr<uint64_t[]> age_;         // creation order per slot
  std::unique_ptr<uint32_t[]> generation_;  // changes only while unpinned (tracker)
  std::unique_ptr<std::atomic<int>[]> pins_;
  std::unique_ptr<std::atomic<bool>[]> map_published_;
  int capacity_ = 0;
  int used_ = 0;
  int recycled_ = 0;
  std::atomic<uint32_t> stale_lookups_{0};
  uint64_t clock_ = 0;
};

}  // namespace rgbdtam

#pragma once
// Saves while running (the board's map.save_period_s), so that a power cut loses at most one
// period of mapping. The loop module's thread owns the places and the graph, so it writes them:
// after steps that changed them, once the period has passed since the last save. The target
// writes beside the map file, syncs and renames, so the file on disk is always one whole save.
// A save holds up the loop module for its length (its queue keeps the keyframes meanwhile);
// the tracker never waits for it.

#include <atomic>
#include <cstdint>

#include "rgbdtam/runtime/map_file.hpp"

namespace rgbdtam {

class MapCheckpoint {
 public:
  // meta: camera, vocabulary and writer; wall_clock: Unix time for the file's header; clock:
  // the loop module's, for the period.
  void init(int64_t period_ns, const MapFileInfo& meta, MapFileTarget* target, ClockFn clock,
            ClockFn wall_clock);
  // The loop module's thread.
  void changed() { dirty_ = true; }
  void save_if_due(const PlaceStore& places, const FixedVector<LoopModule::Edge>& edges);

  // Any thread.
  uint32_t saves() const { return saves_.load(std::memory_order_relaxed); }
  uint32_t failures() const { return failures_.load(std::memory_order_relaxed); }
  // After the loop module's thread has stopped: why the last failed save failed.
  const Status& last_failure() const { return last_failure_; }

 private:
  int64_t period_ns_ = 0;
  MapFileInfo meta_;
  MapFileTarget* target_ = nullptr;
  ClockFn clock_ = nullptr, wall_clock_ = nullptr;
  int64_t last_save_ns_ = 0;
  bool dirty_ = false;
  std::atomic<uint32_t> saves_{0}, failures_{0};
  Status last_failure_;
};

}  // namespace rgbdtam

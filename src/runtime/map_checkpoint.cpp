#include "rgbdtam/runtime/map_checkpoint.hpp"

namespace rgbdtam {

void MapCheckpoint::init(int64_t period_ns, const MapFileInfo& meta, MapFileTarget* target,
                         ClockFn clock, ClockFn wall_clock) {
  period_ns_ = period_ns;
  meta_ = meta;
  target_ = target;
  clock_ = clock;
  wall_clock_ = wall_clock;
  last_save_ns_ = clock();
}

void MapCheckpoint::save_if_due(const PlaceStore& places,
                                const FixedVector<LoopModule::Edge>& edges) {
  const int64_t now = clock_();
  if (!dirty_ || now - last_save_ns_ < period_ns_) return;
  last_save_ns_ = now;
  dirty_ = false;
  MapFileInfo meta = meta_;
  meta.written_unix_ns = wall_clock_();
  // The target's commit refuses a file whose writes failed, naming the error.
  Status s = target_->begin();
  if (s.is_ok()) {
    (void)write_map(places, edges, meta, target_);
    s = target_->commit();
  }
  if (s.is_ok()) {
    saves_.fetch_add(1, std::memory_order_relaxed);
  } else {
    last_failure_ = s;
    failures_.fetch_add(1, std::memory_order_relaxed);
  }
}

}  // namespace rgbdtam

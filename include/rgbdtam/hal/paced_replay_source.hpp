#pragma once
// A recorded sequence delivered as a live sensor would: each frame no earlier than its
// recorded time after the first frame. When the consumer falls behind, the frames that a
// newer one has already overtaken are dropped (newest kept) and counted, as a sensor driver
// that keeps only its latest buffer would.

#include "rgbdtam/hal/tum_replay_source.hpp"

namespace rgbdtam {

class PacedReplaySource : public SensorSource {
 public:
  void attach(TumReplaySource* source) { source_ = source; }
  // Waits for the next due frame; arrival_ns() is when it became available.
  Status next(SensorFrame* frame, Status* warning) override;
  int64_t arrival_ns() const { return arrival_ns_; }
  uint32_t dropped() const { return dropped_; }

 private:
  int64_t due_ns(int index) const;
  TumReplaySource* source_ = nullptr;
  int64_t start_ns_ = -1;
  int64_t first_stamp_ns_ = 0;
  int64_t arrival_ns_ = 0;
  uint32_t dropped_ = 0;
};

}  // namespace rgbdtam

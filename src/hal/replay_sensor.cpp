#include "rgbdtam/hal/replay_sensor.hpp"

#include "rgbdtam/hal/clock.hpp"

namespace rgbdtam {
ReplaySensor::~ReplaySensor() { stop(); }

void ReplaySensor::open(TumReplaySource* source) {
  source_ = source;
  const SensorImageSize& size = source->size();
  for (int i = 0; i < FrameHandoff::kSlots; ++i) {
    handoff_.slot(i).gray.allocate(size.width_px, size.height_px);
    handoff_.slot(i).depth.allocate(size.depth_width_px, size.depth_height_px);
  }
}

Status ReplaySensor::start(const ThreadPlacement& placement) {
  thread_ = std::thread([this] { run(); });
  return place_thread(thread_, placement, "rgbdtam-sensor");
}

void ReplaySensor::stop() {
  handoff_.stop();
  if (thread_.joinable()) thread_.join();
}

void ReplaySensor::run() {
  const int n = source_->frame_count();
  const TumListEntry* stamps = source_->rgb_list().entries.get();
  const int64_t start_ns = monotonic_ns();
  const int64_t first_stamp_ns = n > 0 ? stamps[0].timestamp_ns : 0;
  auto due_ns = [&](int i) { return start_ns + (stamps[i].timestamp_ns - first_stamp_ns); };
  while (!handoff_.stopping() && source_->position() < n) {
    // A frame already overtaken by a newer one is never decoded.
    const int now_index = source_->position();
    int newest = now_index;
    const int64_t now = monotonic_ns();
    while (!held_ && newest + 1 < n && due_ns(newest + 1) <= now) ++newest;
    skipped_.fetch_add(static_cast<uint32_t>(newest - now_index), std::memory_order_relaxed);
    source_->skip_to(newest);
    // Recorded gaps are replayed as they were, however long, so stopping must not wait them out.
    if (handoff_.wait_unless_stopped(due_ns(newest) - monotonic_ns())) break;
    FrameSlot& s = handoff_.back();
    const Status status = source_->next_into(&s.gray, &s.depth, &s.frame, &s.warning);
    if (!status.is_ok()) {
      handoff_.publish_error(status);
      continue;
    }
    s.arrival_ns = monotonic_ns();
    handoff_.publish();
  }
  handoff_.end();
}

Status ReplaySensor::next(SensorFrame* frame, Status* warning) {
  // A gap in the recording is a silent sensor: it times out like the device backends.
  return handoff_.take(kFrameTimeoutMs, "replay", frame, warning);
}

}  // namespace rgbdtam

#include "rgbdtam/hal/replay_sensor.hpp"

#include <chrono>

#include "rgbdtam/hal/clock.hpp"

namespace rgbdtam {
ReplaySensor::~ReplaySensor() { stop(); }

void ReplaySensor::open(TumReplaySource* source) {
  source_ = source;
  const SensorImageSize& size = source->size();
  for (Slot& s : slots_) {
    s.gray.allocate(size.width_px, size.height_px);
    s.depth.allocate(size.depth_width_px, size.depth_height_px);
  }
}

Status ReplaySensor::start(const ThreadPlacement& placement) {
  thread_ = std::thread([this] { run(); });
  return place_thread(thread_, placement, "rgbdtam-sensor");
}

void ReplaySensor::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_.store(true);
  }
  stop_requested_.notify_all();
  published_.notify_all();
  taken_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ReplaySensor::publish() {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (every_frame_) taken_.wait(lock, [this] { return !fresh_ || stopping_.load(); });
    std::swap(back_, middle_);
    if (fresh_) dropped_.fetch_add(1, std::memory_order_relaxed);
    fresh_ = true;
  }
  published_.notify_one();
}

void ReplaySensor::run() {
  const int n = source_->frame_count();
  const TumListEntry* stamps = source_->rgb_list().entries.get();
  const int64_t start_ns = monotonic_ns();
  const int64_t first_stamp_ns = n > 0 ? stamps[0].timestamp_ns : 0;
  auto due_ns = [&](int i) { return start_ns + (stamps[i].timestamp_ns - first_stamp_ns); };
  while (!stopping_.load() && source_->position() < n) {
    // A frame already overtaken by a newer one is never decoded.
    const int now_index = source_->position();
    int newest = now_index;
    const int64_t now = monotonic_ns();
    while (!every_frame_ && newest + 1 < n && due_ns(newest + 1) <= now) ++newest;
    dropped_.fetch_add(static_cast<uint32_t>(newest - now_index), std::memory_order_relaxed);
    source_->skip_to(newest);
    // Recorded gaps are replayed as they were, however long, so stopping must not wait them out.
    {
      std::unique_lock<std::mutex> lock(mutex_);
      stop_requested_.wait_for(lock, std::chrono::nanoseconds(due_ns(newest) - monotonic_ns()),
                               [this] { return stopping_.load(); });
    }
    if (stopping_.load()) break;
    Slot& s = slots_[back_];
    const Status status = source_->next_into(&s.gray, &s.depth, &s.frame, &s.warning);
    if (!status.is_ok()) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = status;
        ++errors_pending_;
      }
      published_.notify_one();
      continue;
    }
    s.arrival_ns = monotonic_ns();
    publish();
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ended_ = true;
  }
  published_.notify_one();
}

Status ReplaySensor::next(SensorFrame* frame, Status* warning) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    // A gap in the recording is a silent sensor: it times out like the device backends.
    if (!published_.wait_for(lock, std::chrono::milliseconds(kFrameTimeoutMs), [this] {
          return fresh_ || errors_pending_ > 0 || ended_ || stopping_.load();
        })) {
      return Status::error(StatusCode::kIoError, "replay: no frame for %d ms", kFrameTimeoutMs);
    }
    if (errors_pending_ > 0) {
      --errors_pending_;
      return error_;
    }
    if (!fresh_) return Status::error(StatusCode::kEndOfStream, "end of sequence");
    std::swap(front_, middle_);
    fresh_ = false;
  }
  taken_.notify_one();
  const Slot& s = slots_[front_];
  *warning = s.warning;
  *frame = s.frame;
  return Status::ok();
}

}  // namespace rgbdtam

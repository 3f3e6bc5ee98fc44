#pragma once
// A sensor thread's frames handed to the tracker, newest first. Three slots rotate: the producer
// fills back() and publishes it as the newest, the consumer takes the newest; a swap under a
// mutex is all either side ever waits for. A frame the consumer did not take in time is
// overwritten by the next and counted as dropped. An error is never overwritten nor overtakes
// a frame: the producer waits until the consumer has taken what is pending, so each error is
// returned by its own take(), after the frames before it, and a device that fails at once cannot
// spin the producer.
//
// hold_every_frame() makes it lossless: publish() waits until the consumer has taken the frame
// before, so that a test sees the same frames however busy the machine (the run stretches
// instead).

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <utility>

#include "rgbdtam/core/image.hpp"
#include "rgbdtam/core/status.hpp"
#include "rgbdtam/port/messages.hpp"

namespace rgbdtam {

// One frame as the producer keeps it: its images (the frame points into them) and when it
// arrived.
struct FrameSlot {
  ImageU8 gray;
  ImageU16 depth;
  SensorFrame frame;
  Status warning;
  int64_t arrival_ns = 0;
};

class FrameHandoff {
 public:
  static constexpr int kSlots = 3;
  // Init time: each slot, to allocate its buffers; and the lossless mode.
  FrameSlot& slot(int i) { return slots_[i]; }
  void hold_every_frame() { every_frame_ = true; }

  // Producer: the slot to fill, then publish() it as the newest frame (or an error, or the end).
  FrameSlot& back() { return slots_[back_]; }
  void publish() {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (every_frame_) taken_.wait(lock, [this] { return !fresh_ || stopping(); });
      std::swap(back_, middle_);
      if (fresh_) dropped_.fetch_add(1, std::memory_order_relaxed);
      fresh_ = true;
    }
    published_.notify_one();
  }
  void publish_error(const Status& error) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      taken_.wait(lock, [this] { return (!error_pending_ && !fresh_) || stopping(); });
      error_ = error;
      error_pending_ = true;
    }
    published_.notify_one();
  }
  void end() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ended_ = true;
    }
    published_.notify_one();
  }
  // Waits `ns` or until stop(), whichever comes first; true when stopping.
  bool wait_unless_stopped(int64_t ns) {
    std::unique_lock<std::mutex> lock(mutex_);
    stop_requested_.wait_for(lock, std::chrono::nanoseconds(ns), [this] { return stopping(); });
    return stopping();
  }
  bool stopping() const { return stopping_.load(); }

  // Consumer: waits up to timeout_ms for a frame newer than the last taken. OK with the newest
  // (valid until the next take()); an error the producer published; kEndOfStream after the end;
  // kIoError naming `who` when nothing came in time.
  Status take(int timeout_ms, const char* who, SensorFrame* frame, Status* warning) {
    Status result;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!published_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [this] {
            return fresh_ || error_pending_ || ended_ || stopping();
          })) {
        return Status::error(StatusCode::kIoError, "%s: no frame for %d ms", who, timeout_ms);
      }
      if (error_pending_) {
        error_pending_ = false;
        result = error_;
      } else if (!fresh_) {
        return Status::error(StatusCode::kEndOfStream, "end of sequence");
      } else {
        std::swap(front_, middle_);
        fresh_ = false;
        *frame = slots_[front_].frame;
        *warning = slots_[front_].warning;
      }
    }
    taken_.notify_one();
    return result;
  }
  // When the frame take() returned last arrived.
  int64_t arrival_ns() const { return slots_[front_].arrival_ns; }
  uint32_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

  // Wakes both sides: the producer stops waiting, the consumer's take() returns.
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_.store(true);
    }
    stop_requested_.notify_all();
    published_.notify_all();
    taken_.notify_all();
  }
  // After stop() and the producer's end: ready for a new producer (a reopened sensor). Frames
  // and errors not taken are let go.
  void restart() {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_.store(false);
    fresh_ = ended_ = error_pending_ = false;
  }

 private:
  FrameSlot slots_[kSlots];
  int back_ = 0, middle_ = 1, front_ = 2;
  bool fresh_ = false;  // middle_ holds a frame the consumer has not taken
  bool ended_ = false;
  bool every_frame_ = false;
  bool error_pending_ = false;
  Status error_;
  std::mutex mutex_;
  std::condition_variable published_;
  std::condition_variable taken_;           // the consumer took the newest frame or the error
  std::condition_variable stop_requested_;  // wakes a producer out of a wait at once
  std::atomic<bool> stopping_{false};
  std::atomic<uint32_t> dropped_{0};
};

}  // namespace rgbdtam

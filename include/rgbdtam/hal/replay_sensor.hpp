#pragma once
// A recorded sequence delivered as a live sensor delivers frames: on its own thread, each frame
// decoded and published no earlier than its recorded time after the first, whether or not the
// tracker is ready. The tracker takes the newest published frame; a frame it did not take in
// time is overwritten (newest kept) and counted as dropped, as is a frame the sensor thread
// could not decode before the next one was due.
//
// Three frame slots rotate: the sensor thread decodes into one, one holds the newest published
// frame, the tracker reads the third; a swap under a mutex is all either side ever waits for. A
// frame that cannot be decoded is reported by next() as an error, never dropped silently.
//
// hold_every_frame() makes it lossless: a frame waits for the tracker to take the one before
// it, so that a test sees the same frames however busy the machine (the run stretches instead).

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "rgbdtam/core/image.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"
#include "rgbdtam/port/thread_placement.hpp"

namespace rgbdtam {

class ReplaySensor : public LiveSensor {
 public:
  static constexpr int kFrameTimeoutMs = 1000;
  ~ReplaySensor() override;
  // Init time: allocates the slots for the (opened) source's frames.
  void open(TumReplaySource* source);
  // Init time: no frame is overtaken or dropped; each waits until the previous one is taken.
  void hold_every_frame() { every_frame_ = true; }
  Status start(const ThreadPlacement& placement) override;
  // Waits for a frame newer than the last one taken (an error after kFrameTimeoutMs);
  // kEndOfStream after the last.
  Status next(SensorFrame* frame, Status* warning) override;
  // When the frame last returned by next() was published by the sensor.
  int64_t arrival_ns() const override { return slots_[front_].arrival_ns; }
  uint32_t dropped() const override { return dropped_.load(std::memory_order_relaxed); }
  void stop() override;

 private:
  struct Slot {
    ImageU8 gray;
    ImageU16 depth;
    SensorFrame frame;
    Status warning;
    int64_t arrival_ns = 0;
  };
  void run();
  void publish();

  TumReplaySource* source_ = nullptr;
  Slot slots_[3];
  int back_ = 0, middle_ = 1, front_ = 2;
  bool fresh_ = false;  // middle_ holds a frame the tracker has not taken
  bool ended_ = false;
  bool every_frame_ = false;
  // Frames that could not be delivered are never overwritten like frames: each one is
  // reported by its own next() call (with the latest message).
  int errors_pending_ = 0;
  Status error_;
  std::mutex mutex_;
  std::condition_variable published_;
  std::condition_variable taken_;           // the tracker took the newest frame (every_frame_)
  std::condition_variable stop_requested_;  // wakes the replay thread out of a gap at once
  std::atomic<bool> stopping_{false};
  std::atomic<uint32_t> dropped_{0};
  std::thread thread_;
};

}  // namespace rgbdtam

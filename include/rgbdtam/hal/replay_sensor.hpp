#pragma once
// A recorded sequence delivered as a live sensor delivers frames: on its own thread, each frame
// decoded and published no earlier than its recorded time after the first, whether or not the
// tracker is ready. The tracker takes the newest published frame (FrameHandoff); a frame it did
// not take in time is overwritten and counted as dropped, as is a frame the sensor thread could
// not decode before the next one was due. A frame that cannot be decoded is reported by next()
// as an error, never dropped silently.
//
// hold_every_frame() makes it lossless: a frame waits for the tracker to take the one before
// it, so that a test sees the same frames however busy the machine (the run stretches instead).

#include <atomic>
#include <thread>

#include "rgbdtam/core/image.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"
#include "rgbdtam/port/frame_handoff.hpp"
#include "rgbdtam/port/thread_placement.hpp"

namespace rgbdtam {

class ReplaySensor : public LiveSensor {
 public:
  static constexpr int kFrameTimeoutMs = 1000;
  ~ReplaySensor() override;
  // Init time: allocates the slots for the (opened) source's frames.
  void open(TumReplaySource* source);
  // Init time: no frame is overtaken or dropped; each waits until the previous one is taken.
  void hold_every_frame() {
    held_ = true;
    handoff_.hold_every_frame();
  }
  Status start(const ThreadPlacement& placement) override;
  // Waits for a frame newer than the last one taken (an error after kFrameTimeoutMs);
  // kEndOfStream after the last.
  Status next(SensorFrame* frame, Status* warning) override;
  // When the frame last returned by next() was published by the sensor.
  int64_t arrival_ns() const override { return handoff_.arrival_ns(); }
  uint32_t dropped() const override {
    return handoff_.dropped() + skipped_.load(std::memory_order_relaxed);
  }
  void stop() override;

 private:
  void run();

  TumReplaySource* source_ = nullptr;
  FrameHandoff handoff_;
  bool held_ = false;
  std::atomic<uint32_t> skipped_{0};  // overtaken before they were decoded
  std::thread thread_;
};

}  // namespace rgbdtam

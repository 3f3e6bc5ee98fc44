#pragma once
// A sensor whose depth comes from a camera of its own, read and its depth registered to colour
// on a thread of its own (the board's sensor.registration_thread), so that registration runs
// beside tracking instead of before it: on a Raspberry Pi 4 with a D435, registration's 12-18 ms
// a frame and tracking's 18 ms do not fit one core's 33 ms, on two they do. The tracker takes
// frames ready to track, newest first (FrameHandoff). It sits under the stall recovery: a reopen
// pauses the thread (once the sensor's read in progress returns), reopens the sensor and resumes
// it; the thread is made once, at start.

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "rgbdtam/port/frame_handoff.hpp"
#include "rgbdtam/port/sensor_source.hpp"
#include "rgbdtam/runtime/depth_in_colour.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

class RegisteringSensor : public LiveSensor {
 public:
  static constexpr int kFrameTimeoutMs = 1000;
  ~RegisteringSensor() override;
  // Init time: reads `sensor` (opened, not started) and registers its depth as params say.
  void init(LiveSensor* sensor, const Params& params);
  // Bytes init allocates for these params: the registration's tables and the frames handed over.
  static size_t bytes_needed(const Params& params);
  // Init time: no frame is overtaken (FrameHandoff::hold_every_frame).
  void hold_every_frame() { handoff_.hold_every_frame(); }
  // The sensor's start, then this thread on the same placement.
  Status start(const ThreadPlacement& placement) override;
  // The newest frame, its depth in the colour camera (an error after kFrameTimeoutMs without
  // one); the sensor's errors and end, each in turn.
  Status next(SensorFrame* frame, Status* warning) override;
  int64_t arrival_ns() const override { return handoff_.arrival_ns(); }
  uint32_t dropped() const override {
    return sensor_dropped_.load(std::memory_order_relaxed) + handoff_.dropped();
  }
  void stop() override;

 protected:
  Status open_stream() override;
  void close_stream() override;

 private:
  void run();
  // The thread's side of a pause: false when it is to end.
  bool wait_while_paused();

  LiveSensor* sensor_ = nullptr;
  DepthInColour registration_;
  FrameHandoff handoff_;
  std::atomic<uint32_t> sensor_dropped_{0};  // the sensor's own count, read on this thread
  std::mutex state_mutex_;
  std::condition_variable state_changed_;
  bool running_ = false;  // asked to read: false pauses the thread
  bool paused_ = false;   // the thread is paused, outside the sensor
  bool quit_ = false;
  std::thread thread_;
};

}  // namespace rgbdtam

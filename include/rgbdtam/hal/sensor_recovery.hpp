#pragma once
// Stall recovery for a live sensor: when no frame has arrived for stall_ns, the sensor's USB
// device is reset (when the board names it) and the stream reopened, retried every retry_ns
// within reopen_budget_ns while the device re-enumerates. Each attempt is one error from next()
// that says what was done, so it reaches the operator like any sensor error; the first frame
// after it is counted as a recovery with its time since the stall began.

#include <cstdint>

#include "rgbdtam/hal/usb_devices.hpp"
#include "rgbdtam/port/sensor_source.hpp"

namespace rgbdtam {

struct RecoveryConfig {
  int64_t stall_ns = 1'000'000'000;          // no frame for this long: the stream is stalled
  int64_t reopen_budget_ns = 3'000'000'000;  // reopen attempts after a reset, within this time
  int64_t retry_ns = 100'000'000;            // between reopen attempts
  int64_t error_interval_ns = 33'000'000;    // errors no closer than this (one frame period)
  bool reset_usb = false;
  UsbId usb;
  const char* sysfs_root = "/sys";
  const char* devfs_root = "/dev";
};

struct RecoveryCounters {
  uint32_t stalls = 0;
  uint32_t usb_resets = 0;  // resets the kernel accepted
  uint32_t usb_reset_failures = 0;
  uint32_t reopens = 0;  // streams opened again
  uint32_t reopen_failures = 0;
  uint32_t recoveries = 0;  // frames flowing again after a stall
  int64_t last_recovery_ns = 0;
  int64_t max_recovery_ns = 0;  // stall start (last frame) to the first frame after it
};

using NowFn = int64_t (*)();
using SleepUntilFn = void (*)(int64_t deadline_ns);

class SensorRecovery : public LiveSensor {
 public:
  void init(LiveSensor* sensor, const RecoveryConfig& config, NowFn now, SleepUntilFn sleep_until);
  Status start(const ThreadPlacement& placement) override;
  Status next(SensorFrame* frame, Status* warning) override;
  void stop() override { sensor_->stop(); }
  int64_t arrival_ns() const override { return sensor_->arrival_ns(); }
  uint32_t dropped() const override { return sensor_->dropped(); }
  const RecoveryCounters& counters() const { return counters_; }

 private:
  Status recover(int64_t now_ns, const Status& cause);

  LiveSensor* sensor_ = nullptr;
  RecoveryConfig config_;
  NowFn now_ = nullptr;
  SleepUntilFn sleep_until_ = nullptr;
  int64_t last_frame_ns_ = 0;
  int64_t last_error_ns_ = INT64_MIN / 2;
  int64_t next_recovery_ns_ = 0;
  bool stalled_ = false;
  RecoveryCounters counters_;
};

}  // namespace rgbdtam

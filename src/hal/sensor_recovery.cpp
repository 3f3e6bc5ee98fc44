#include "rgbdtam/hal/sensor_recovery.hpp"

#include <cstdio>

namespace rgbdtam {

void SensorRecovery::init(LiveSensor* sensor, const RecoveryConfig& config, NowFn now,
                          SleepUntilFn sleep_until) {
  sensor_ = sensor;
  config_ = config;
  now_ = now;
  sleep_until_ = sleep_until;
}

Status SensorRecovery::start(const ThreadPlacement& placement) {
  last_frame_ns_ = now_();
  return sensor_->start(placement);
}

Status SensorRecovery::next(SensorFrame* frame, Status* warning) {
  const Status s = sensor_->next(frame, warning);
  int64_t now = now_();
  if (s.is_ok()) {
    if (stalled_) {
      stalled_ = false;
      ++counters_.recoveries;
      counters_.last_recovery_ns = now - last_frame_ns_;
      if (counters_.last_recovery_ns > counters_.max_recovery_ns) {
        counters_.max_recovery_ns = counters_.last_recovery_ns;
      }
    }
    last_frame_ns_ = now;
    return s;
  }
  if (s.code() == StatusCode::kEndOfStream) return s;
  // A dead device answers at once: errors are paced so that it cannot spin the tracker.
  if (now - last_error_ns_ < config_.error_interval_ns) {
    sleep_until_(last_error_ns_ + config_.error_interval_ns);
    now = now_();
  }
  last_error_ns_ = now;
  if (now - last_frame_ns_ < config_.stall_ns || now < next_recovery_ns_) return s;
  return recover(now, s);
}

Status SensorRecovery::recover(int64_t now_ns, const Status& cause) {
  if (!stalled_) {
    stalled_ = true;
    ++counters_.stalls;
  }
  char reset[300] = "";
  if (config_.reset_usb) {
    char node[128] = "";
    const Status r =
        reset_usb_device(config_.sysfs_root, config_.devfs_root, config_.usb, node, sizeof(node));
    if (r.is_ok()) {
      ++counters_.usb_resets;
      std::snprintf(reset, sizeof(reset), "; USB reset ok (%s)", node);
    } else {
      ++counters_.usb_reset_failures;
      std::snprintf(reset, sizeof(reset), "; USB reset failed (%s)", r.message());
    }
  }
  // After a reset the device re-enumerates: its nodes come back within the budget, or not.
  const int64_t deadline = now_ns + config_.reopen_budget_ns;
  Status opened = sensor_->reopen();
  while (!opened.is_ok() && opened.code() != StatusCode::kInvalidArgument &&
         now_() + config_.retry_ns <= deadline) {
    sleep_until_(now_() + config_.retry_ns);
    opened = sensor_->reopen();
  }
  opened.is_ok() ? ++counters_.reopens : ++counters_.reopen_failures;
  // The reopened stream gets a full stall period to deliver before the next attempt.
  last_error_ns_ = now_();
  next_recovery_ns_ = last_error_ns_ + config_.stall_ns;
  // The outcome first: a STATUSTEXT carries only the first 42 characters after "sensor: ".
  const long long stalled_ms = (now_ns - last_frame_ns_) / 1'000'000;
  if (opened.is_ok()) {
    return Status::error(StatusCode::kIoError, "stall %lld ms: stream reopened%s; last error: %s",
                         stalled_ms, reset, cause.message());
  }
  return Status::error(StatusCode::kIoError, "stall %lld ms: reopen failed: %s%s", stalled_ms,
                       opened.message(), reset);
}

}  // namespace rgbdtam

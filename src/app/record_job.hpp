#pragma once
// `rgbdtam record --board board/<name> <out-dir>`: what the board's sensor delivers, written as a
// TUM RGB-D folder that replay reads (tracking does not run).

#include <atomic>

#include "rgbdtam/hal/replay_sensor.hpp"
#include "rgbdtam/hal/tum_recorder.hpp"
#include "run_job.hpp"

namespace rgbdtam {

class RecordJob {
 public:
  Status init(const RunOptions& options, const char* out_dir);
  Status start();
  // One frame from the sensor into the recorder; false at the end or after request_stop().
  bool step();
  void request_stop() { stop_requested_.store(true); }
  // Writes what is queued; the first write error, if any.
  Status finish();
  void print_summary() const;

  uint32_t frames() const { return frames_; }
  uint32_t sensor_dropped() const { return sensor_.live->dropped(); }
  const TumRecorder& recorder() const { return recorder_; }

 private:
  RunOptions options_;
  Board board_;
  Params params_;
  BoardSensor sensor_;
  TumRecorder recorder_;
  uint32_t frames_ = 0;
  uint32_t sensor_errors_ = 0;
  int64_t started_ns_ = 0;
  int64_t wall_ns_ = 0;
  std::atomic<bool> stop_requested_{false};
};

}  // namespace rgbdtam

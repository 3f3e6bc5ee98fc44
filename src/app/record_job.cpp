#include "record_job.hpp"

#include <cstdio>

#include "rgbdtam/hal/clock.hpp"

namespace rgbdtam {

Status RecordJob::init(const RunOptions& options, const char* out_dir) {
  options_ = options;
  RGBDTAM_RETURN_IF_ERROR(load_board_and_params(options, &board_, &params_));
  // A recording keeps the depth as its camera measured it, to be registered when replayed.
  board_.sensor_registration_thread = false;
  RGBDTAM_RETURN_IF_ERROR(open_board_sensor(board_, params_, &sensor_));
  return recorder_.open(out_dir, sensor_image_size(params_));
}

Status RecordJob::start() {
  // The recorder's disk work goes where the board puts the mapper: no mapping while recording.
  RGBDTAM_RETURN_IF_ERROR(recorder_.start(board_.mapper));
  RGBDTAM_RETURN_IF_ERROR(sensor_.live->start(board_.sensor));
  started_ns_ = monotonic_ns();
  return Status::ok();
}

bool RecordJob::step() {
  if (stop_requested_.load() || recorder_.failed() ||
      (options_.max_frames > 0 && frames_ >= static_cast<uint32_t>(options_.max_frames))) {
    return false;
  }
  SensorFrame frame;
  Status warning;
  const Status s = sensor_.live->next(&frame, &warning);
  if (s.code() == StatusCode::kEndOfStream) return false;
  if (!s.is_ok()) {
    ++sensor_errors_;
    std::fprintf(stderr, "rgbdtam record: %s\n", s.message());
    return true;
  }
  ++frames_;
  (void)recorder_.push(frame);  // a full queue is counted by the recorder
  return true;
}

Status RecordJob::finish() {
  wall_ns_ = monotonic_ns() - started_ns_;
  sensor_.live->stop();
  return recorder_.finish();
}

void RecordJob::print_summary() const {
  const RecorderCounters c = recorder_.counters();
  const LatencyStats& t = recorder_.time_per_frame();
  const double seconds = wall_ns_ * 1e-9;
  std::printf(
      "recorded: %u frames from the sensor in %.1f s (%.1f Hz); %u colour and %u depth "
      "images written, %.1f MB\n",
      frames_, seconds, seconds > 0 ? frames_ / seconds : 0.0, c.written, c.depth_written,
      c.bytes / 1e6);
  std::printf(
      "dropped: %u at the recorder's queue, %u by the sensor (newest kept); sensor "
      "errors %u\n",
      c.dropped, sensor_.live->dropped(), sensor_errors_);
  std::printf("recorder ms/frame (encode + write): median %.2f, p95 %.2f, max %.2f\n",
              t.percentile_ms(0.5), t.percentile_ms(0.95), t.max_ms());
}

}  // namespace rgbdtam

#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {

Status SlamSystem::init(const Params& params, ClockFn clock, MapSink* sink) {
  params_ = params;
  RGBDTAM_RETURN_IF_ERROR(tracking_.init(params));
  if (params.map_enabled) {
    queue_.allocate(params.map_queue_frames, params.camera.width_px, params.camera.height_px);
    RGBDTAM_RETURN_IF_ERROR(mapper_.init(params, params.camera, clock, sink));
    tracking_.connect_mapper(&queue_);
  }
  return Status::ok();
}

Status SlamSystem::start(const ThreadPlacement& mapper) {
  if (!params_.map_enabled || !params_.map_threaded) return Status::ok();
  return thread_.start(&queue_, &mapper_, mapper);
}

PoseEstimate SlamSystem::process(const SensorFrame& frame) {
  const PoseEstimate pose = track(frame);
  map_pending();
  return pose;
}

void SlamSystem::map_pending() {
  if (!params_.map_enabled) return;
  if (params_.map_threaded) {
    thread_.notify();
  } else {
    // Deterministic replay: the mapper takes its step here, between frames.
    while (MapperFrame* f = queue_.front()) {
      mapper_.step(*f);
      queue_.pop();
    }
  }
}

void SlamSystem::finish() {
  if (!params_.map_enabled || finished_) return;
  finished_ = true;
  if (params_.map_threaded) {
    thread_.stop();
  } else {
    mapper_.finish();
  }
}

}  // namespace rgbdtam

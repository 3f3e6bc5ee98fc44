#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {

MemoryNeed memory_need(const Params& p) {
  // The pyramids, undistortion maps and scratch images of the tracker and of the mapper, per
  // pixel of the camera; measured by test_allocations (it counts what init allocates).
  constexpr size_t kTrackerImageBytesPerPixel = 94, kMapperImageBytesPerPixel = 86;
  const size_t pixels = static_cast<size_t>(p.camera.width_px) * p.camera.height_px;
  const size_t seeds = p.map_enabled ? static_cast<size_t>(p.map_seeds) : 0;
  MemoryNeed m;
  m.per_keyframe = KeyframeBuilder::keyframe_bytes(p.camera, p.tracker) + seeds * sizeof(MapPoint);
  m.keyframe_pool = m.per_keyframe * static_cast<size_t>(p.keyframe_pool_size);
  if (p.map_enabled) {
    MultiViewOptions mv;
    mv.max_seeds = p.map_seeds;
    constexpr size_t kQueueBytesPerPixel = sizeof(float) * 2 + 1;  // MapperFrame's images
    m.mapper = static_cast<size_t>(p.map_queue_frames) * pixels * kQueueBytesPerPixel +
               MappingModule::kOpenKeyframes * SeedMap::bytes_needed(mv) +
               seeds * (sizeof(FusedPixel) + 2 * sizeof(MapPoint));  // + the local maps
  }
  m.images =
      pixels * (kTrackerImageBytesPerPixel + (p.map_enabled ? kMapperImageBytesPerPixel : 0));
  return m;
}

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

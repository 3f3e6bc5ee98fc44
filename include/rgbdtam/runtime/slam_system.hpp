#pragma once
// Tracking and mapping wired together: the tracking pipeline, its queue to the mapper, and the
// mapper, stepped synchronously after each frame (deterministic replay) or on its own thread.
// init() allocates everything, start() starts the mapper thread; process() never allocates.

#include "rgbdtam/runtime/mapping.hpp"
#include "rgbdtam/runtime/thread_placement.hpp"
#include "rgbdtam/runtime/tracking_pipeline.hpp"

namespace rgbdtam {

// What SlamSystem::init allocates for a configuration, by the keys that size it, so that a
// configuration the machine cannot hold is refused with their names instead of aborting.
struct MemoryNeed {
  size_t per_keyframe = 0;   // points, map points and the slot
  size_t keyframe_pool = 0;  // map.keyframe_pool of them
  size_t mapper = 0;         // map.queue_frames frames, map.seeds seeds and their maps
  size_t images = 0;         // pyramids and scratch images, from camera.width x camera.height
  size_t total() const { return keyframe_pool + mapper + images; }
};
MemoryNeed memory_need(const Params& params);

class SlamSystem {
 public:
  Status init(const Params& params, ClockFn clock, MapSink* sink);
  // Starts the mapper's thread when map.threaded (after init, as every thread is).
  Status start(const ThreadPlacement& mapper = ThreadPlacement());
  // track() then map_pending().
  PoseEstimate process(const SensorFrame& frame);
  PoseEstimate track(const SensorFrame& frame) { return tracking_.process(frame); }
  // Synchronous mode: the mapper's step for what the tracker queued. Threaded: a wake-up.
  void map_pending();
  // Lets the mapper finish what is queued and the keyframe in progress.
  void finish();

  const TrackingPipeline& tracking() const { return tracking_; }
  const MappingModule& mapper() const { return mapper_; }

 private:
  Params params_;
  TrackingPipeline tracking_;
  MapperQueue queue_;
  MappingModule mapper_;
  MappingThread thread_;
  bool finished_ = false;
};

}  // namespace rgbdtam

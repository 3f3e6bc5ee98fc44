#pragma once
// Tracking and mapping wired together: the tracking pipeline, its queue to the mapper, and the
// mapper, stepped synchronously after each frame (deterministic replay) or on its own thread.
// init() allocates everything, start() starts the mapper thread; process() never allocates.

#include "rgbdtam/runtime/mapping.hpp"
#include "rgbdtam/runtime/thread_placement.hpp"
#include "rgbdtam/runtime/tracking_pipeline.hpp"

namespace rgbdtam {

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

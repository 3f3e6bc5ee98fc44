#pragma once
// The tracking module: sensor frame -> frontend (undistortion, pyramids) -> tracker ->
// keyframe decision -> pose estimate. Everything is sized in init(); process() never allocates.
// Thread: the caller's (replay: main thread; runtime: the tracking task).

#include "rgbdtam/runtime/keyframe_pool.hpp"
#include "rgbdtam/runtime/mapping.hpp"
#include "rgbdtam/runtime/messages.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

struct TrackingCounters {
  uint32_t frames = 0;
  uint32_t tracked = 0;
  uint32_t lost = 0;
  uint32_t without_depth = 0;
  uint32_t keyframes = 0;
  uint32_t resets = 0;
  uint32_t reused = 0;                    // keyframe switches that reused an earlier keyframe
  uint32_t mapper_dropped_frames = 0;     // the mapper queue was full
  uint32_t mapper_dropped_keyframes = 0;  // ... on a new keyframe: it keeps its sensor map
};

class TrackingPipeline {
 public:
  Status init(const Params& params);
  PoseEstimate process(const SensorFrame& frame);
  // Every tracked frame is offered to the mapper through this queue (never waiting on it).
  void connect_mapper(MapperQueue* queue) { mapper_queue_ = queue; }

  const TrackingCounters& counters() const { return counters_; }
  const KeyframePool& keyframes() const { return pool_; }
  const Params& params() const { return params_; }

 private:
  void start_keyframe(const SensorFrame& frame, const SE3& T_w_c, PoseEstimate* out);
  SE3 predict_pose() const;
  void offer_to_mapper(const PoseEstimate& pose, bool new_keyframe);
  void propagate_map(const SE3& T_w_c);
  void adopt_map(Keyframe* kf);
  bool reuse_keyframe(const SE3& T_w_c, PoseEstimate* out);

  Params params_;
  Undistorter undistorter_;
  FramePyramid pyramid_;
  FramePyramid propagated_;  // sensor depth plus the local maps (photometric points only)
  // The last two keyframe maps the tracker adopted (the authors' "local maps"), in the world.
  struct LocalMap {
    FixedVector<MapPoint> points;  // keyframe frame
    SE3 T_w_k;
  };
  LocalMap local_maps_[2];
  int next_local_map_ = 0;
  ImageU16 depth_undistorted_;
  KeyframeBuilder builder_;
  KeyframePool pool_;
  Tracker tracker_;
  Keyframe* reference_ = nullptr;
  MapperQueue* mapper_queue_ = nullptr;
  uint32_t next_keyframe_id_ = 0;
  // Last two valid poses for the constant-velocity prediction.
  SE3 T_w_last_, T_w_before_last_;
  int valid_history_ = 0;
  int consecutive_lost_ = 0;
  float typical_photometric_sigma_ = 0.f;  // slow average over tracked frames; 0 = none yet
  uint32_t reset_counter_ = 0;
  TrackingCounters counters_;
};

}  // namespace rgbdtam

#pragma once
// The tracking module: sensor frame -> frontend (undistortion, pyramids) -> pose search and
// health checks -> keyframe decision -> pose estimate. process() is the list of stages a frame
// goes through; each concern it touches has one owner (runtime/tracking/):
//   FrameBuffers      the current frame and the last valid one
//   MotionState       last pose, time, velocity, validity, prediction, restart, correction
//   CorrectionBlend   small loop corrections taken up gradually by the poses sent
//   MotionPriors      other sensors' motion (the autopilot's rotation), where priors plug in
//   PoseSearch        the tracker, its guesses and the health checks
//   KeyframeHandover  the reference keyframe, building, adopting and mapping keyframes
//   LoopLink          keyframes out to the loop module, corrections in, relocalisation
//   DepthUnitsGuard   whether the depth is read in the sensor's units
// Everything is sized in init(); process() never allocates.
// Thread: the caller's (replay: main thread; runtime: the tracking task).

#include "rgbdtam/core/attitude.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/runtime/keyframe_building.hpp"
#include "rgbdtam/runtime/keyframe_pool.hpp"
#include "rgbdtam/runtime/loop_closing.hpp"
#include "rgbdtam/runtime/mapping.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "rgbdtam/runtime/tracking/correction_blend.hpp"
#include "rgbdtam/runtime/tracking/depth_units_guard.hpp"
#include "rgbdtam/runtime/tracking/frame_buffers.hpp"
#include "rgbdtam/runtime/tracking/keyframe_handover.hpp"
#include "rgbdtam/runtime/tracking/loop_link.hpp"
#include "rgbdtam/runtime/tracking/motion_priors.hpp"
#include "rgbdtam/runtime/tracking/motion_state.hpp"
#include "rgbdtam/runtime/tracking/pose_search.hpp"

namespace rgbdtam {

// The stages' own counts; each part keeps its own.
struct StageCounters {
  uint32_t frames = 0;
  uint32_t tracked = 0;
  uint32_t lost = 0;
  uint32_t without_depth = 0;
  uint32_t depth_not_surface = 0;     // ... of which the sensor's depth was set aside as noise
  uint32_t depth_frozen = 0;          // ... or repeated the last depth frame: lost
  uint32_t depth_units_off = 0;       // ... or was not in the sensor's units: lost
  uint32_t retried = 0;               // frames whose first estimate failed a health check
  uint32_t recovered_by_guesses = 0;  // ... and passed from another initial guess
  uint32_t recovered_by_left_keyframe = 0;   // ... or against the keyframe reuse had just left
  uint32_t recovered_by_last_frame = 0;      // ... or against the last valid frame
  uint32_t relocalised = 0;                  // lost frames found again in the map
  uint32_t relocalised_on_new_keyframe = 0;  // ... on a new keyframe, not the place's own
  uint32_t relocalised_past_the_pool = 0;    // ... at a place whose dense keyframe was recycled
  uint32_t withheld = 0;                     // tracked frames not reported valid after a correction
};

// Every tracking counter, the stages' and each part's (TrackingPipeline::counters()).
struct TrackingCounters : StageCounters,
                          MotionCounters,
                          PriorCounters,
                          SearchCounters,
                          HandoverCounters,
                          LoopLinkCounters {};

class TrackingPipeline {
 public:
  // keyframes: the dense keyframe store, allocated here, shared with the mapper; building: where
  // new keyframes are built, allocated here (synchronous unless its queue is connected).
  Status init(const Params& params, KeyframePool* keyframes, KeyframeBuildTask* building,
              ClockFn clock = nullptr);
  PoseEstimate process(const SensorFrame& frame);
  // For the next process() only: the camera's turn since the last tracked frame, as another
  // sensor saw it (from last_tracked_ns() to the frame's stamp; otherwise ignored).
  void set_rotation_prior(const RotationPrior& prior) { priors_.set_rotation(prior); }
  int64_t last_tracked_ns() const { return motion_.last_tracked_ns(); }
  // The keyframe a frame asked for is ordered after its pose is out: here, or at the next
  // process() at the latest. Synchronous building builds and adopts it here; otherwise it is
  // adopted at the first process() after it is built. Until then the previous keyframe stays
  // the reference.
  void build_pending_keyframe();
  // Every tracked frame is offered to the mapper through this queue (never waiting on it).
  void connect_mapper(MapperQueue* queue) { keyframes_.connect_mapper(queue); }
  // New keyframes go to the loop module; its corrections come back; lost frames are looked up
  // in the places. Init time.
  void connect_loop(LoopQueue* keyframes, CorrectionQueue* corrections, PlaceStore* places,
                    const Vocabulary* vocabulary) {
    loop_.connect(params_, keyframes, corrections, places, vocabulary);
  }

  // A map was loaded into the places: no pose is reported until a frame is found among them,
  // and keyframes are numbered after the map's. Init time, after connect_loop.
  void start_in_loaded_map(uint32_t next_keyframe_id);
  uint32_t next_keyframe_id() const { return keyframes_.next_keyframe_id(); }

  TrackingCounters counters() const;
  // The reading that found the depth in other units than the sensor's (conclusive false: none).
  const DepthUnitsReading& depth_units_off() const { return depth_units_.off_reading(); }
  // The depth was found in other units for the run: what was sent is no trajectory.
  bool depth_units_wrong() const { return depth_units_.latched_off(); }
  const KeyframePool& keyframes() const { return keyframes_.pool(); }
  const Params& params() const { return params_; }
  // The keyframe's pose now (loop corrections included), if it is still in the pool.
  bool keyframe_pose(uint32_t id, SE3* T_w_k) const { return keyframes_.pose_of(id, T_w_k); }

 private:
  // The stages of process(), in order.
  PoseEstimate begin_output(const SensorFrame& frame);
  // The sensor checks the frame failed (kDepthFrozen), 0 when none.
  uint32_t prepare(const SensorFrame& frame, PoseEstimate* out);
  void start(const SensorFrame& frame, PoseEstimate* out);  // no keyframe yet
  void adopt_built_keyframe();
  void adopt_corrections();
  Attempt estimate(int64_t t_ns);
  // After the reference failed (first): the other searches, cheapest first.
  Attempt recover(const Attempt& first, int64_t t_ns);
  // continuous: tracked from the last valid pose (not relocalised).
  void accept(const Attempt& a, const SensorFrame& frame, PoseEstimate* out, bool continuous);
  // An earlier keyframe taken up again instead of a new one; else *window measures the new
  // keyframe against the one that sees most of it, when it was tracked for reuse, and
  // *window_later asks the keyframe builder to measure it against the local window's others
  // (and that one, when too little of it is in view for reuse).
  bool reuse_keyframe(const Attempt& current, int64_t t_ns, PoseEstimate* out, KeyframeLink* window,
                      WindowRequest* window_later);
  bool relocalise(const SensorFrame& frame, PoseEstimate* out);
  void find_in_loaded_map(const SensorFrame& frame, PoseEstimate* out);
  void on_lost(const SensorFrame& frame, uint32_t failed, PoseEstimate* out);
  void report(int64_t t_ns, PoseEstimate* out);
  // The pose goes out as the consumers see it: a correction being blended in (CorrectionBlend).
  void send(PoseEstimate* out);

  Params params_;
  Undistorter undistorter_;
  FrameBuffers frames_;
  FrozenDepthCheck frozen_depth_;
  DepthUnitsGuard depth_units_;
  MotionState motion_;
  CorrectionBlend blend_;
  MotionPriors priors_;
  PoseSearch search_;
  KeyframeHandover keyframes_;
  LoopLink loop_;
  bool localising_ = false;  // in a loaded map, not found in it yet
  StageCounters counters_;
};

}  // namespace rgbdtam

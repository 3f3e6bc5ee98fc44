#pragma once
// Tracking and mapping wired together: the tracking pipeline, the keyframe builder, its queue to
// the mapper, and the mapper, stepped synchronously after each frame (deterministic replay) or
// on threads of their own.
// init() allocates everything, start() starts the mapper thread; process() never allocates.

#include "rgbdtam/port/thread_placement.hpp"
#include "rgbdtam/runtime/depth_in_colour.hpp"
#include "rgbdtam/runtime/map_checkpoint.hpp"
#include "rgbdtam/runtime/map_file.hpp"
#include "rgbdtam/runtime/mapping.hpp"
#include "rgbdtam/runtime/tracking_pipeline.hpp"

namespace rgbdtam {

// What SlamSystem::init allocates for a configuration, by the keys that size it, so that a
// configuration the machine cannot hold is refused with their names instead of aborting.
struct MemoryNeed {
  size_t per_keyframe = 0;   // points, map points and the slot
  size_t keyframe_pool = 0;  // map.keyframe_pool of them
  size_t mapper = 0;         // map.queue_frames frames, map.seeds seeds and their maps
  size_t images = 0;         // pyramids and scratch images, from camera.width x camera.height
  size_t loop = 0;           // loop.places light records, their index and pose graph, the queue
  size_t total() const { return keyframe_pool + mapper + images + loop; }
};
// vocabulary_words: of the vocabulary loop closure will use; 0 when it is off.
MemoryNeed memory_need(const Params& params, int vocabulary_words = 0);

class SlamSystem {
 public:
  // vocabulary: loop closure and relocalisation need one (loop.enabled); null turns them off.
  Status init(const Params& params, ClockFn clock, MapSink* sink,
              const Vocabulary* vocabulary = nullptr);
  // After init, before start: the places and graph of a map file (loop closure on). Tracking
  // then reports no pose until it finds the camera among them; poses are in the map's world.
  Status load_map(const uint8_t* data, size_t size, MapFileInfo* info);
  // After finish(): the places and graph as a map file. meta: time and writer.
  Status write_map(MapFileInfo meta, ByteSink* out) const;
  // meta with what a map file of this system says of the camera and vocabulary (loop closure
  // on).
  MapFileInfo map_meta(MapFileInfo meta) const;
  // After init, before start: saves while running, on the loop module's thread (loop.threaded,
  // map.mode slam).
  Status set_checkpoint(MapCheckpoint* checkpoint);
  // Starts the keyframe builder's and mapper's threads when map.threaded, the loop module's
  // when loop.threaded (after init, as every thread is).
  Status start(const ThreadPlacement& mapper = ThreadPlacement(),
               const ThreadPlacement& loop = ThreadPlacement(),
               const ThreadPlacement& builder = ThreadPlacement());
  // track() then map_pending().
  PoseEstimate process(const SensorFrame& frame);
  // The frame's depth is moved into the colour camera first where it comes from a camera of its
  // own (depth_camera.register).
  PoseEstimate track(const SensorFrame& frame) {
    return tracking_.process(depth_in_colour_.apply(frame));
  }
  // The frame last tracked, its depth in the colour camera (what obstacles are measured in).
  // Until the next track().
  const SensorFrame& last_frame() const { return depth_in_colour_.last(); }
  // The next frame's turn as another sensor saw it (TrackingPipeline::set_rotation_prior).
  void set_rotation_prior(const RotationPrior& prior) { tracking_.set_rotation_prior(prior); }
  // After the pose is out: the keyframe the frame asked for is ordered (if it did not,
  // nothing) ...
  void build_pending_keyframe() { tracking_.build_pending_keyframe(); }
  // ... then, synchronous mode: the mapper's and loop module's steps for what the tracker
  // queued; threaded: a wake-up. Builds the pending keyframe first if it is still due.
  void map_pending();
  // Synchronous mode: the loop module's and the mapper's steps in the last map_pending() and
  // their time (a clock given to init), for traces of each module's work per frame.
  struct Steps {
    int items = 0;
    int64_t ns = 0;
  };
  const Steps& last_loop_steps() const { return last_loop_; }
  const Steps& last_mapper_steps() const { return last_mapper_; }
  // Lets the mapper finish what is queued and the keyframe in progress.
  void finish();

  const TrackingPipeline& tracking() const { return tracking_; }
  const MappingModule& mapper() const { return mapper_; }
  const KeyframeBuildTask& keyframe_building() const { return building_; }
  const LoopModule& loop() const { return loop_; }
  // The places (loop.places records), for what they hold and have forgotten.
  const PlaceStore& places() const { return places_; }
  // A keyframe's pose as the map has it now (loop corrections included): from the tracker's
  // pool, else from the places. Tracker's thread.
  bool keyframe_pose(uint32_t keyframe_id, SE3* T_w_k);
  bool loop_enabled() const { return loop_on_; }
  // Init time: tools that check place recognition receive every verified match.
  void set_loop_observer(LoopObserver* observer) { loop_.set_observer(observer); }

 private:
  Params params_;
  DepthInColour depth_in_colour_;
  KeyframePool keyframes_;  // dense tier; the light tier is places_
  TrackingPipeline tracking_;
  KeyframeBuildTask building_;
  KeyframeOrderQueue build_queue_;
  KeyframeBuildThread build_thread_;
  MapperQueue queue_;
  MappingModule mapper_;
  MappingThread thread_;
  bool loop_on_ = false;
  const Vocabulary* vocabulary_ = nullptr;
  LoopQueue loop_queue_;
  CorrectionQueue corrections_;
  PlaceStore places_;
  LoopModule loop_;
  WorkerThread<LoopKeyframe, LoopModule> loop_thread_;
  bool finished_ = false;
  ClockFn clock_ = nullptr;
  Steps last_loop_, last_mapper_;
};

}  // namespace rgbdtam

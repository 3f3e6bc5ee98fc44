#pragma once
// The tracking module: sensor frame -> frontend (undistortion, pyramids) -> tracker ->
// health checks -> keyframe decision -> pose estimate. The keyframes it decides on are built by
// the keyframe building module and adopted between frames. Everything is sized in init();
// process() never allocates.
// Thread: the caller's (replay: main thread; runtime: the tracking task).

#include "rgbdtam/core/attitude.hpp"
#include "rgbdtam/runtime/keyframe_building.hpp"
#include "rgbdtam/runtime/keyframe_pool.hpp"
#include "rgbdtam/runtime/loop_closing.hpp"
#include "rgbdtam/runtime/mapping.hpp"
#include "rgbdtam/runtime/messages.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "rgbdtam/runtime/relocaliser.hpp"

namespace rgbdtam {

struct TrackingCounters {
  uint32_t frames = 0;
  uint32_t tracked = 0;
  uint32_t lost = 0;
  uint32_t without_depth = 0;
  uint32_t depth_not_surface = 0;  // ... of which the sensor's depth was set aside as noise
  uint32_t keyframes = 0;
  uint32_t frames_awaiting_keyframe = 0;  // tracked against the last one while the next was built
  uint32_t keyframes_stale = 0;  // built after a reset or correction moved the map: not adopted
  uint32_t resets = 0;
  uint32_t reused = 0;                    // keyframe switches that reused an earlier keyframe
  uint32_t mapper_dropped_frames = 0;     // the mapper queue was full
  uint32_t mapper_dropped_keyframes = 0;  // ... on a new keyframe: it keeps its sensor map
  uint32_t single_term = 0;           // frames whose pose came from one term, the other not fitting
  uint32_t retried = 0;               // frames whose first estimate failed a health check
  uint32_t recovered_by_guesses = 0;  // ... and passed from another initial guess
  uint32_t recovered_by_last_frame = 0;      // ... or against the last valid frame
  uint32_t relocalised = 0;                  // lost frames found again in the map
  uint32_t relocalised_on_new_keyframe = 0;  // ... on a new keyframe, not the place's own
  uint32_t relocalised_past_the_pool = 0;    // ... at a place whose dense keyframe was recycled
  uint32_t loop_corrections = 0;             // loop closures adopted
  uint32_t withheld = 0;                     // tracked frames not reported valid after a correction
  uint32_t loop_dropped_keyframes = 0;  // the loop queue was full: not remembered (or a reuse lost)
  uint32_t prior_used = 0;      // frames whose first guess turned by the autopilot's attitude stood
  uint32_t prior_rejected = 0;  // ... did not (the image disagreed): tracked without it
};

class TrackingPipeline {
 public:
  // keyframes: the dense keyframe store, allocated here, shared with the mapper; building: where
  // new keyframes are built, allocated here (synchronous unless its queue is connected).
  Status init(const Params& params, KeyframePool* keyframes, KeyframeBuildTask* building,
              ClockFn clock = nullptr);
  PoseEstimate process(const SensorFrame& frame);
  // For the next process() only: the camera's turn since the last tracked frame, as another
  // sensor saw it (from last_tracked_ns() to the frame's stamp; otherwise ignored).
  void set_rotation_prior(const RotationPrior& prior) { prior_ = prior; }
  int64_t last_tracked_ns() const { return has_last_ ? last_ns_ : -1; }
  // The keyframe a frame asked for is ordered after its pose is out: here, or at the next
  // process() at the latest. Synchronous building builds and adopts it here; otherwise it is
  // adopted at the first process() after it is built. Until then the previous keyframe stays
  // the reference.
  void build_pending_keyframe();
  // Every tracked frame is offered to the mapper through this queue (never waiting on it).
  void connect_mapper(MapperQueue* queue) { mapper_queue_ = queue; }
  // New keyframes go to the loop module; its corrections come back; lost frames are looked up
  // in the places. Init time.
  void connect_loop(LoopQueue* keyframes, CorrectionQueue* corrections, PlaceStore* places,
                    const Vocabulary* vocabulary);

  // A map was loaded into the places: no pose is reported until a frame is found among them,
  // and keyframes are numbered after the map's. Init time, after connect_loop.
  void start_in_loaded_map(uint32_t next_keyframe_id);
  uint32_t next_keyframe_id() const { return next_keyframe_id_; }

  const TrackingCounters& counters() const { return counters_; }
  const KeyframePool& keyframes() const { return *pool_; }
  const Params& params() const { return params_; }
  // The keyframe's pose now (loop corrections included), if it is still in the pool.
  bool keyframe_pose(uint32_t id, SE3* T_w_k) const;

 private:
  // What ties a new keyframe into the map's graph: the keyframe or place it was measured
  // against, how, the measurement, and its information (graph convention).
  struct KeyframeLink {
    uint32_t reference_id = 0;
    EdgeKind kind = EdgeKind::kRestart;
    SE3 T_reference_keyframe;
    Matrix6d information = Matrix6d::Zero();
  };
  // A tracking result against one keyframe and the health checks it failed.
  struct Attempt {
    Keyframe* kf = nullptr;
    TrackResult r;
    uint32_t failed = ~0u;
    SE3 T_w_c() const { return kf->T_w_k * r.T_k_c; }
  };
  FramePyramid& frame() { return frames_[current_]; }
  Attempt track_against(Keyframe* kf, const SE3& T_w_guess, int64_t t_ns);
  // From the prediction, turned by the rotation prior where there is one and the image agrees.
  Attempt track_first(int64_t t_ns);
  bool prior_applies(int64_t t_ns) const;
  SE3 turned_by_prior(const SE3& predicted) const;
  // The wider basin: several initial guesses screened at the coarsest level.
  Attempt track_from_guesses(Keyframe* kf, int64_t t_ns);
  Attempt without_misfit_term(const Attempt& a, int64_t t_ns);
  uint32_t failed_checks(const TrackResult& r, Keyframe* kf, int64_t t_ns);
  bool unique_along_weak_direction(const TrackResult& r, Keyframe* kf);
  bool relocalise(const SensorFrame& frame, PoseEstimate* out);
  void find_in_loaded_map(const SensorFrame& frame, PoseEstimate* out);
  void adopt_corrections();
  void apply_correction(const LoopCorrection& c);
  // A free slot of the loop module's queue, or null (no loop module, or full: counted).
  LoopKeyframe* loop_slot();
  void offer_to_loop(const Keyframe& kf, const KeyframeLink& link, const FramePyramid& f);
  void offer_reuse_to_loop(const Attempt& left, const Attempt& taken);
  // The link of a keyframe at T_w_c tracked against the reference with this information.
  KeyframeLink odometry_link(const SE3& T_w_c, const Matrix6d& tracker_information) const;
  KeyframeLink restart_link() const;
  SE3 predict_pose(int64_t t_ns) const;
  Keyframe* keyframe_from_last_valid_frame();
  void accept(const Attempt& a, const SensorFrame& frame, PoseEstimate* out);
  void on_lost(const SensorFrame& frame, uint32_t failed, PoseEstimate* out);
  PoseEstimate track(const SensorFrame& frame);
  // This frame becomes a keyframe at T_w_k once its pose is out (build_pending_keyframe); false
  // while another is being built. to_mapper: the mapper maps it (a restart is not mapped).
  bool ask_for_keyframe(const SE3& T_w_k, const KeyframeLink& link, bool to_mapper,
                        PoseEstimate* out);
  void adopt_built_keyframe();
  // keyframe_edges: the frame is a new keyframe (the reference) with these Canny edges.
  void offer_to_mapper(const PoseEstimate& pose, const FramePyramid& f,
                       const ImageU8* keyframe_edges);
  void adopt_map(Keyframe* kf);
  bool reuse_keyframe(const Attempt& current, int64_t t_ns, PoseEstimate* out);

  Params params_;
  Undistorter undistorter_;
  // The current frame and the last valid one, swapped when a frame is valid.
  FramePyramid frames_[2];
  int current_ = 0;
  bool last_valid_frame_kept_ = false;  // frames_[1 - current_] is the frame of last_ns_
  // The last two keyframe maps the tracker adopted, copied into each keyframe order.
  LocalMap local_maps_[KeyframeBuildTask::kLocalMaps];
  int next_local_map_ = 0;
  KeyframeBuilder builder_;  // the last valid frame's keyframe while tracking fails, at once
  KeyframePool* pool_ = nullptr;
  KeyframeBuildTask* building_ = nullptr;
  Tracker tracker_;
  Keyframe* reference_ = nullptr;
  Keyframe* fallback_ = nullptr;  // built from the last valid frame while tracking fails
  MapperQueue* mapper_queue_ = nullptr;
  LoopQueue* loop_queue_ = nullptr;
  CorrectionQueue* corrections_ = nullptr;
  PlaceStore* places_ = nullptr;
  const Vocabulary* vocabulary_ = nullptr;
  Relocaliser relocaliser_;
  uint32_t corrections_adopted_ = 0;
  uint32_t pending_flags_ = 0;     // for the next output: a correction moved the map
  int64_t withhold_until_ns_ = 0;  // poses up to this time are tracked but not reported valid
  uint32_t next_keyframe_id_ = 0;
  bool localising_ = false;  // in a loaded map, not found in it yet
  struct PendingKeyframe {
    bool due = false;      // asked for, not ordered yet
    int frame_buffer = 0;  // frames_[frame_buffer] is the keyframe's frame until ordered
    SE3 T_w_k;
    KeyframeLink link;
    bool to_mapper = false;
    PoseEstimate pose;           // the frame's, offered to the mapper with the keyframe
    uint32_t reset_counter = 0;  // when ordered: a reset or correction since makes it stale
  };
  PendingKeyframe pending_keyframe_;
  // The last valid pose and the camera's twist (v, omega per second) before it.
  SE3 T_w_last_;
  int64_t last_ns_ = 0;
  RotationPrior prior_;  // this frame's, if any
  Vector6d velocity_ = Vector6d::Zero();
  bool has_last_ = false;
  bool previous_valid_ = false;  // the frame before this one was valid
  int64_t lost_since_ns_ = -1;   // the first lost frame of the current loss; -1 when tracking
  ReferenceScales typical_;      // slow averages over healthy frames
  uint32_t reset_counter_ = 0;
  TrackingCounters counters_;
};

}  // namespace rgbdtam

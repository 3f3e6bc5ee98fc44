#pragma once
// The tracker's keyframes: which one is the reference, the keyframe a frame asks for until it is
// ordered from the keyframe building module and adopted, the keyframe built at once from the
// last valid frame while tracking fails, the maps the mapper publishes (and the two local maps
// kept from them for the next keyframe's sensor-blind pixels), the frames offered to the mapper,
// and the pool's keyframes moved by a loop correction. Thread: the tracker's.

#include <cstdint>

#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/runtime/keyframe_building.hpp"
#include "rgbdtam/runtime/keyframe_pool.hpp"
#include "rgbdtam/runtime/mapping.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "rgbdtam/runtime/tracking/frame_buffers.hpp"
#include "rgbdtam/runtime/tracking/keyframe_link.hpp"

namespace rgbdtam {

struct HandoverCounters {
  uint32_t keyframes = 0;
  uint32_t frames_awaiting_keyframe = 0;  // tracked against the last one while the next was built
  uint32_t keyframes_stale = 0;           // built after a restart or relocalisation: not adopted
  uint32_t reused = 0;                    // keyframe switches that reused an earlier keyframe
  uint32_t mapper_dropped_frames = 0;     // the mapper queue was full
  uint32_t mapper_dropped_keyframes = 0;  // ... on a new keyframe: it keeps its sensor map
};

class KeyframeHandover {
 public:
  // pool: the dense keyframe store, allocated here, shared with the mapper; building: where new
  // keyframes are built, allocated here (synchronous unless its queue is connected).
  void init(const Params& params, KeyframePool* pool, KeyframeBuildTask* building, ClockFn clock);
  // A keyframe sized as every keyframe of the pool (for the tracker's scratch).
  void allocate_model(Keyframe* kf) const { builder_.allocate_keyframe(kf); }
  // Every tracked frame is offered to the mapper through this queue (never waiting on it).
  void connect_mapper(MapperQueue* queue) { mapper_queue_ = queue; }
  bool mapping() const { return mapper_queue_ != nullptr; }
  // Keyframes of a loaded map are numbered before this one.
  void start_at(uint32_t next_keyframe_id) { next_keyframe_id_ = next_keyframe_id; }
  uint32_t next_keyframe_id() const { return next_keyframe_id_; }

  // The keyframe frames are tracked against; null before the first.
  Keyframe* reference() const { return reference_; }
  // A healthy frame was tracked against kf: it is the reference.
  void track_against(Keyframe* kf);
  // An earlier keyframe is taken up again (map reuse).
  void take_up(Keyframe* kf);
  // The keyframe the last take_up left, while the reference is the one taken up and it is still
  // in the pool, in the estimate's frame; else null. It fitted the frame before the reference
  // did: a frame the taken-up keyframe does not fit may still fit it.
  Keyframe* left() const;
  // The last valid frame's keyframe is no longer the estimate's (a restart, a relocalisation).
  void forget_fallback() { fallback_ = nullptr; }
  // The last valid frame as a keyframe (sensor depth only), built at once on the first call of
  // a failure; null when there is no such frame or it is the reference's own.
  Keyframe* from_last_valid_frame(const FrameBuffers& frames, const SE3& T_w_last, int64_t last_ns);

  // How a keyframe at T_w_c tracked against the reference with this information links to it;
  // and a keyframe that is not linked (a restart).
  KeyframeLink odometry_link(const SE3& T_w_c, const Matrix6d& tracker_information) const;
  KeyframeLink restart_link() const;

  // A keyframe is being built: no other can be asked for.
  bool building() const { return !building_->idle(); }
  void count_frame_awaiting() { ++counters_.frames_awaiting_keyframe; }
  // The frame in frame_slot becomes a keyframe at T_w_k once its pose is out (order_pending);
  // false while another is being built. to_mapper: the mapper maps it (a restart is not).
  // window: a further measurement of it, against an earlier keyframe (kind kRestart: none), and
  // window_later: those the keyframe builder makes after the build.
  bool ask(const SE3& T_w_k, const KeyframeLink& link, bool to_mapper, int frame_slot,
           PoseEstimate* out, const KeyframeLink& window = KeyframeLink(),
           const WindowRequest& window_later = WindowRequest());
  bool due() const { return pending_.due; }
  // The asking frame's pose, as tracking measured it: offered to the mapper with the keyframe.
  void set_due_pose(const PoseEstimate& pose) { pending_.pose = pose; }
  // Orders the keyframe asked for, if one is due; map: the camera's world now (MotionState).
  void order_pending(const FrameBuffers& frames, const MapFrame& map);
  // Once built: the keyframe in its pool slot as the new reference, moved with the map if a loop
  // correction moved it meanwhile (null when none is built, or it was stale: the map began a new
  // epoch). Its link and frame stay readable until release_adopted().
  Keyframe* adopt_built(const MapFrame& map);
  const KeyframeLink& adopted_link() const { return pending_.link; }
  // The local window's measurements of the adopted keyframe: the tracker's, then the builder's.
  WindowLinks adopted_window_links() const;
  const FramePyramid& adopted_frame() const { return building_->frame(); }
  // The adopted keyframe goes to the mapper (if it asked to be mapped); the builder is free.
  void release_adopted();

  // Swaps in the map the mapper published for kf, if any, and keeps it as a local map.
  void adopt_map(Keyframe* kf);
  // Every finished map, not only the reference's: the local maps that fill a new keyframe's
  // sensor-blind pixels must be the newest, and the mapper may finish a keyframe after the
  // tracker has moved on from it.
  void adopt_all_maps();
  // A valid frame for the mapper, its pose in the world of map (keyframe_edges: it is the new
  // reference, with these edges).
  void offer_to_mapper(const PoseEstimate& pose, const MapFrame& map, const FramePyramid& f,
                       const ImageU8* keyframe_edges);

  // Moves each keyframe the correction knows to its corrected pose, and newer ones with the
  // newest it knows; camera_delta: how the reference moved (T_w'_w). False if nothing moved.
  bool move_by(const LoopCorrection& c, SE3* camera_delta);

  Keyframe* find(uint32_t id);
  bool pose_of(uint32_t id, SE3* T_w_k) const;
  // Up to `wanted` keyframes other than the reference nearest to T_w_c, nearest first (a radian
  // of rotation counted as 0.3 m), of those in the estimate's frame.
  int nearest(const SE3& T_w_c, int wanted, Keyframe** out);
  // A restart places the camera at its last valid pose, not where it is: the keyframes before
  // it are in another frame until a relocalisation or a loop correction joins the two.
  void restarted() {
    oldest_in_frame_id_ = next_keyframe_id_;
    taken_up_ = nullptr;
  }
  void joined() { oldest_in_frame_id_ = 0; }
  bool pinned(const Keyframe* kf) const { return pool_->pinned(kf); }
  const KeyframePool& pool() const { return *pool_; }

  const HandoverCounters& counters() const { return counters_; }

 private:
  struct PendingKeyframe {
    bool due = false;      // asked for, not ordered yet
    int frame_buffer = 0;  // the keyframe's frame stays in this slot until ordered
    SE3 T_w_k;
    KeyframeLink link;
    KeyframeLink window;
    bool to_mapper = false;
    PoseEstimate pose;  // the frame's, offered to the mapper with the keyframe
    MapFrame map;       // when ordered
  };

  KeyframePool* pool_ = nullptr;
  KeyframeBuildTask* building_ = nullptr;
  KeyframeBuilder builder_;  // the last valid frame's keyframe while tracking fails, at once
  KeyframeAliasFinder aliases_;
  double alias_range_m_ = 0.0;
  MapperQueue* mapper_queue_ = nullptr;
  Keyframe* reference_ = nullptr;
  Keyframe* fallback_ = nullptr;  // built from the last valid frame while tracking fails
  // Left by the last take_up (its slot's generation: while the slot still holds it), for as
  // long as the keyframe taken up is the reference.
  KeyframeHandle left_;
  Keyframe* taken_up_ = nullptr;
  PendingKeyframe pending_;
  uint32_t next_keyframe_id_ = 0;
  uint32_t oldest_in_frame_id_ = 0;  // keyframes before it: not in the estimate's frame
  // The last two keyframe maps the tracker adopted, copied into each keyframe order.
  LocalMap local_maps_[KeyframeBuildTask::kLocalMaps];
  int next_local_map_ = 0;
  HandoverCounters counters_;
};

}  // namespace rgbdtam

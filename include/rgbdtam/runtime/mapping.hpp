#pragma once
// The mapping module (paper sec. V). The tracker hands it every tracked frame through a
// bounded single-producer single-consumer queue of fixed slots; the mapper estimates the newest
// keyframe's multi-view inverse depth, fuses it with the sensor's, and publishes the keyframe's
// refreshed photometric points to the tracker (KeyframePool::publish_map). step() is the same code
// whether a replay drains the queue synchronously or the mapper's own thread does.
//
// Queue policy when full: the tracker never waits. The frame is not queued and is counted in
// dropped_frames; when it was a new keyframe, that keyframe keeps its sensor-only map and is
// counted in dropped_keyframes.
// When late (half the queue or more waits behind the frame in hand), the mapper catches up by
// observing no frame but keyframes, so that a slow board thins the maps instead of losing
// keyframes (counted in frames_skipped_late). Synchronous replay drains the queue after every
// frame, so it is never late.

#include <memory>

#include "rgbdtam/core/multiview.hpp"
#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/port/latency_stats.hpp"
#include "rgbdtam/port/map_sink.hpp"
#include "rgbdtam/port/spsc_ring.hpp"
#include "rgbdtam/port/thread_placement.hpp"
#include "rgbdtam/port/worker.hpp"
#include "rgbdtam/runtime/keyframe_pool.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

// Tracker -> mapper frames; MapperQueue::allocate sizes each slot's images.
class MapperQueue : public SpscRing<MapperFrame> {
 public:
  void allocate(int slots, int width, int height);
};

struct MappingCounters {
  uint32_t keyframes_mapped = 0;
  uint32_t frames_observed = 0;
  uint32_t frames_skipped_late = 0;  // not observed: the queue was backing up
  uint64_t points_sensor = 0;        // edge pixels whose depth is the sensor's alone
  uint64_t points_multiview = 0;     // ... multi-view alone (the sensor saw nothing there)
  uint64_t points_fused = 0;         // ... both, fused by inverse variance
  // Summed over the fused pixels: the multi-view's share of each one's inverse-depth
  // information (1 - sigma_fused^2 / sigma_sensor^2), what the views add beside the sensor.
  double fused_multiview_share_sum = 0;
};

class MappingModule {
 public:
  static constexpr int kOpenKeyframes = 3;  // params.cpp sizes the keyframe pool for this
  Status init(const Params& params, const PinholeIntrinsics& k, ClockFn clock, MapSink* sink,
              KeyframePool* keyframes);
  // Init time: the queue this module's frames come through, to see when it is late.
  void connect_queue(const MapperQueue* queue) { queue_ = queue; }
  void step(const MapperFrame& frame);
  // Finishes the keyframe in progress (end of stream).
  void tick() {}
  void finish();
  const MappingCounters& counters() const { return counters_; }
  const LatencyStats& time_per_keyframe() const { return per_keyframe_; }

 private:
  // One keyframe being mapped. A keyframe stays open after the next one arrives, until its
  // own frame budget is spent, so that quickly replaced keyframes are still triangulated.
  struct Job {
    Keyframe* keyframe = nullptr;  // null when the slot is free
    KeyframeHandle handle;
    SeedMap seeds;
    ImageF gray;                  // the keyframe's level-0 image, for matching
    ImageF sensor_inverse_depth;  // the keyframe's own
    ImageU8 edges;                // its Canny edges, from the tracker
    SE3 T_w_last_used;
    float median_depth_m = 1.f;
    int frames_used = 0;
    uint64_t started = 0;  // arrival order
    int64_t spent_ns = 0;
  };
  // Spaced frames from before the newest keyframe: a new keyframe is first matched against
  // them (as the authors' code reuses the previous keyframe's frames), so that the pixels the
  // camera is about to leave behind are seen from the other side too.
  struct EarlierFrame {
    ImageF gray;
    SE3 T_w_c;
  };
  static constexpr int kEarlierFrames = 4;
  void start(Job* job, const MapperFrame& frame);
  void observe(Job* job, const ImageF& gray, const SE3& T_w_c);
  void remember(const MapperFrame& frame);
  bool late() const;
  double spacing_m(const SE3& a, const SE3& b) const;
  void finalize(Job* job);

  Params params_;
  KeyframePool* keyframes_ = nullptr;
  const MapperQueue* queue_ = nullptr;
  MultiViewOptions mv_;
  ClockFn clock_ = nullptr;
  MapSink* sink_ = nullptr;
  Job jobs_[kOpenKeyframes];
  uint64_t arrivals_ = 0;
  EarlierFrame earlier_[kEarlierFrames];
  int earlier_count_ = 0;  // valid entries; the newest is earlier_[(earlier_next_ + 3) % 4]
  int earlier_next_ = 0;
  MapFrame map_frame_;         // the world of the open keyframes' and earlier frames' poses
  float scene_depth_m_ = 1.f;  // the newest keyframe's median depth, to space earlier frames
  KeyframeBuilder builder_;
  FramePyramid fused_;  // the finishing keyframe's grey pyramid and fused inverse depth
  FixedVector<FusedPixel> pixels_;
  MappingCounters counters_;
  LatencyStats per_keyframe_;
};

using MappingThread = WorkerThread<MapperFrame, MappingModule>;

}  // namespace rgbdtam

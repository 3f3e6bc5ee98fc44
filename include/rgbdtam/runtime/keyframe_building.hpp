#pragma once
// The keyframe building module: the keyframe a frame asked for is built off the tracker's thread,
// from copies of the frame's level-0 images (and of the local maps that fill its sensor-blind
// pixels), and adopted by the tracker between frames, as the mapper's maps are. Until then the
// tracker tracks against the previous keyframe. One keyframe is in flight at a time.
// Synchronous mode (no queue connected: replay, tests) builds in submit(), on the caller's
// thread, between frames, so that a replay is bit-identical run to run.
// Threads: the tracker writes the order's buffers while idle() and reads the result once
// built(); the builder's thread (or submit(), synchronously) builds in between. The ring's order
// and the `built_` flag hand the buffers over, each way.

#include <atomic>

#include "rgbdtam/core/keyframe_aliases.hpp"
#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/port/latency_stats.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/port/spsc_ring.hpp"
#include "rgbdtam/port/worker.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "rgbdtam/runtime/tracking/window_measurement.hpp"

namespace rgbdtam {

// A keyframe map the tracker adopted (the authors' "local maps"), in the world.
struct LocalMap {
  FixedVector<MapPoint> points;  // keyframe frame
  SE3 T_w_k;
};

using KeyframeOrderQueue = SpscRing<KeyframeOrder>;

class KeyframeBuildTask {
 public:
  static constexpr int kLocalMaps = 2;
  // What allocate() takes, in bytes.
  static size_t bytes_needed(const Params& params, int map_points);
  // clock: times each build (null: not timed).
  void allocate(const Params& params, int map_points, ClockFn clock = nullptr);
  // Threaded mode, init time: orders go to the builder's thread through this ring.
  void connect_queue(KeyframeOrderQueue* queue) { queue_ = queue; }

  // Tracker. While idle(), the order's inputs may be written: the frame's level-0 grey image
  // and sensor inverse depth, and the local maps.
  bool idle() const { return !in_flight_; }
  ImageF& gray_level0() { return frame_.gray(0); }
  ImageF& inverse_depth_level0() { return frame_.inverse_depth_level0(); }
  LocalMap& local_map(int i) { return local_maps_[i]; }
  // The local window's measurement of the keyframe, made after it is built; ordered while
  // idle(), read once built().
  WindowMeasurement& window() { return window_; }
  const WindowMeasurement& window() const { return window_; }
  // at_once: built here, on the caller's thread, in threaded mode too (nothing is in flight, so
  // the builder's thread is idle).
  void submit(const KeyframeOrder& order, bool at_once = false);
  // Tracker, between frames: true once the ordered keyframe is built; then hand_over() moves its
  // points into the pool's slot, and frame() and edges() are the keyframe's until release().
  bool built() const { return in_flight_ && built_.load(std::memory_order_acquire); }
  void hand_over(Keyframe* kf);
  const FramePyramid& frame() const { return frame_; }
  const ImageU8& edges() const { return builder_.edges(); }
  void release();

  // Builder's thread (WorkerThread), or submit() synchronously.
  void step(const KeyframeOrder& order);
  void tick() {}
  void finish() {}
  const LatencyStats& time_per_keyframe() const { return per_keyframe_; }
  // The last build's time; read it on the builder's thread (or synchronously) only.
  int64_t last_build_ns() const { return last_build_ns_; }

 private:
  void fill_sensor_blind_pixels(const SE3& T_w_c);

  KeyframeOrderQueue* queue_ = nullptr;
  ClockFn clock_ = nullptr;
  KeyframeBuilder builder_;
  KeyframeAliasFinder aliases_;
  double alias_range_m_ = 0.0;
  FramePyramid frame_;       // the keyframe's grey images and sensor inverse depth
  FramePyramid propagated_;  // ... its inverse depth with the local maps where the sensor is blind
  LocalMap local_maps_[kLocalMaps];
  Keyframe keyframe_;  // its points, until handed over
  WindowMeasurement window_;
  bool in_flight_ = false;  // tracker's: submitted, not released
  std::atomic<bool> built_{false};
  LatencyStats per_keyframe_;  // builder's thread
  int64_t last_build_ns_ = 0;
};

using KeyframeBuildThread = WorkerThread<KeyframeOrder, KeyframeBuildTask>;

}  // namespace rgbdtam

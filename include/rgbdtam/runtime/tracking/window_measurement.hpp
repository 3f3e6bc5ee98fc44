#pragma once
// The local window's further measurements of a new keyframe (loop.window): its frame tracked
// against earlier keyframes that see much of it, off the tracker's core. The tracker asks for
// them with the keyframes and the keyframe builder's thread measures them after the build, with
// a copy of each keyframe's points and a search of its own, judged as the tracker judges a
// tracking made once the frame's pose is out: the same health checks at the tracker's typical
// scales, with no reach left to search.
// Threads: the tracker orders while the builder is idle and reads the result once the keyframe
// is built; the builder measures in between (the build's handover orders both ways).

#include <cstddef>
#include <cstdint>

#include "rgbdtam/runtime/params.hpp"
#include "rgbdtam/runtime/tracking/keyframe_link.hpp"
#include "rgbdtam/runtime/tracking/motion_state.hpp"
#include "rgbdtam/runtime/tracking/pose_search.hpp"

namespace rgbdtam {

// What the tracker knows when it asks: the earlier keyframes, the frame's pose, and how it
// judges (its motion and typical scales at that frame).
struct WindowRequest {
  const Keyframe* references[kMaxWindowEdges] = {};
  int count = 0;  // 0: nothing to measure
  SE3 T_w_c;
  MotionState motion;
  ReferenceScales typical;
  int64_t t_ns = 0;
};

class WindowMeasurement {
 public:
  // What allocate() takes, in bytes (nothing when loop.window is off).
  static size_t bytes_needed(const Params& params);
  // builder: sizes the copied keyframes as every keyframe.
  void allocate(const Params& params, const KeyframeBuilder& builder);
  // How many keyframes one request may hold (loop.window_keyframes; 0 when off).
  int capacity() const { return capacity_; }

  // Tracker, while the builder is idle: the request's keyframes are copied.
  void order(const WindowRequest& request);
  // Builder's thread: frame is the new keyframe's.
  void measure(const FramePyramid& frame);
  // Tracker, once built: the healthy measurements, in the request's order.
  const WindowLinks& links() const { return links_; }

 private:
  int capacity_ = 0;
  double covariance_scale_ = 1.0;
  Keyframe references_[kMaxWindowEdges];  // the request's keyframes, copied
  WindowRequest request_;
  PoseSearch search_;
  WindowLinks links_;
};

}  // namespace rgbdtam

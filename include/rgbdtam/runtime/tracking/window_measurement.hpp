#pragma once
// The local window's second measurement of a new keyframe (loop.window): its frame tracked
// against the earlier keyframe that sees most of it, off the tracker's core. The tracker asks
// for it with the keyframe and the keyframe builder's thread measures it after the build, with
// a copy of that keyframe's points and a search of its own, judged as the tracker judges a
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

// What the tracker knows when it asks: the earlier keyframe, the frame's pose, and how it
// judges (its motion and typical scales at that frame).
struct WindowRequest {
  const Keyframe* reference = nullptr;  // null: nothing to measure
  SE3 T_w_c;
  MotionState motion;
  ReferenceScales typical;
  int64_t t_ns = 0;
};

class WindowMeasurement {
 public:
  // What allocate() takes, in bytes (nothing when loop.window is off).
  static size_t bytes_needed(const Params& params);
  // builder: sizes the copied keyframe as every keyframe.
  void allocate(const Params& params, const KeyframeBuilder& builder);

  // Tracker, while the builder is idle: the request's keyframe is copied.
  void order(const WindowRequest& request);
  // Builder's thread: frame is the new keyframe's.
  void measure(const FramePyramid& frame);
  // Tracker, once built: whether one was ordered, and its link (kind kRestart: not healthy).
  bool ordered() const { return request_.reference != nullptr; }
  const KeyframeLink& link() const { return link_; }

 private:
  bool allocated_ = false;
  double covariance_scale_ = 1.0;
  Keyframe reference_;  // the request's keyframe, copied
  WindowRequest request_;
  PoseSearch search_;
  KeyframeLink link_;
};

}  // namespace rgbdtam

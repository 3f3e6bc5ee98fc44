#pragma once
// The tracker's two frame pyramids: the current frame's, and the last valid frame's, which a
// failed frame can be tracked against again and a keyframe can be built from. A valid frame
// becomes the last valid one by swapping the two, never by copying.
// Thread: the tracker's.

#include "rgbdtam/core/pyramid.hpp"

namespace rgbdtam {

class FrameBuffers {
 public:
  void allocate(const PinholeIntrinsics& camera, double depth_factor, const DepthRange& range) {
    for (FramePyramid& f : frames_) f.allocate(camera, depth_factor, range);
  }
  FramePyramid& current() { return frames_[current_]; }
  const FramePyramid& current() const { return frames_[current_]; }
  // The last valid frame, or null when there is none (before the first, after a restart).
  const FramePyramid* last_valid() const { return kept_ ? &frames_[1 - current_] : nullptr; }
  // A buffer by slot: a keyframe's frame stays in its slot until the keyframe is ordered.
  int current_slot() const { return current_; }
  const FramePyramid& slot(int i) const { return frames_[i]; }
  // The current frame becomes the last valid one; the next frame goes into the other buffer.
  void keep_current() {
    current_ = 1 - current_;
    kept_ = true;
  }
  // A restart: the last valid frame no longer belongs to the estimate.
  void forget_last_valid() { kept_ = false; }

 private:
  FramePyramid frames_[2];
  int current_ = 0;
  bool kept_ = false;
};

}  // namespace rgbdtam

#pragma once
// The frames of a recorded TUM sequence as the tracker's frontend sees them (undistorted grey
// and sensor inverse depth at full resolution, registered to colour as the tracker takes it), for
// offline commands and tools. Allocates at open().

#include "rgbdtam/core/pyramid.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"
#include "rgbdtam/runtime/depth_in_colour.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

class FrontendFrames {
 public:
  Status open(const char* sequence, const Params& params);
  int count() const { return source_.frame_count(); }
  int64_t timestamp_ns(int i) const { return source_.rgb_list().entries[i].timestamp_ns; }
  // Frame i into frame(); false when it cannot be read or has no depth.
  bool load(int i);
  const FramePyramid& frame() const { return frame_; }

 private:
  TumReplaySource source_;
  DepthInColour depth_in_colour_;
  Undistorter undistorter_;
  FramePyramid frame_;
};

}  // namespace rgbdtam

#pragma once
// A source of RGB-D frames: a recorded sequence or a live sensor. Frames from every source
// reach the tracking pipeline along the same path.

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/runtime/messages.hpp"

namespace rgbdtam {

class SensorSource {
 public:
  virtual ~SensorSource() = default;
  // Delivers the next frame. kEndOfStream ends the stream. Any other error means one frame
  // was skipped (its message says why) and the caller may call again. `warning` is set when
  // a frame is delivered degraded (e.g. without depth).
  virtual Status next(SensorFrame* frame, Status* warning) = 0;
};

}  // namespace rgbdtam

#pragma once
// A source of RGB-D frames: a recorded sequence or a live sensor. Frames from every source
// reach the tracking pipeline along the same path.

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/port/thread_placement.hpp"

namespace rgbdtam {

class SensorSource {
 public:
  virtual ~SensorSource() = default;
  // Delivers the next frame. kEndOfStream ends the stream. Any other error means one frame
  // was skipped (its message says why) and the caller may call again. `warning` is set when
  // a frame is delivered degraded (e.g. without depth).
  virtual Status next(SensorFrame* frame, Status* warning) = 0;
};

// A sensor the firmware runtime drives: it delivers frames at its own rate, started after
// init. next() waits for the next frame and always returns the newest one; frames overtaken
// meanwhile are dropped and counted.
class LiveSensor : public SensorSource {
 public:
  virtual Status start(const ThreadPlacement& placement) = 0;
  virtual void stop() = 0;
  // When the frame last returned by next() arrived (CLOCK_MONOTONIC ns).
  virtual int64_t arrival_ns() const = 0;
  virtual uint32_t dropped() const = 0;
  // Closes the stream and opens it again as first opened (after a stall or a USB reset), ready
  // for next(); the frame buffers stay. A failed attempt leaves it closed, so the next one
  // starts clean.
  Status reopen() {
    close_stream();
    const Status s = open_stream();
    if (!s.is_ok()) close_stream();
    return s;
  }

 protected:
  // The device half of a backend's open and close, which reopen() repeats. Sensors that cannot
  // stall keep these and say so.
  virtual Status open_stream() {
    return Status::error(StatusCode::kInvalidArgument, "this sensor cannot be reopened");
  }
  virtual void close_stream() {}
};

}  // namespace rgbdtam

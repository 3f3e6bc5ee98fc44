#pragma once
// The frame as the tracker and the obstacle reporter take it: its depth in the colour camera.
// A sensor that registers depth itself passes through; one whose depth comes from a camera of
// its own (depth_camera.register), at that camera's size, has it moved into the colour camera
// here, into a buffer allocated at init.

#include "rgbdtam/core/depth_registration.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

class DepthInColour {
 public:
  // Where the registered depth goes: a buffer of this object's (apply), or only the caller's
  // (apply_into: a sensor thread that keeps several frames needs no buffer here).
  enum class Buffer { kOwn, kCallers };
  // Init time.
  void init(const Params& params, Buffer buffer = Buffer::kOwn);
  // The frame with its depth in the colour camera; valid until the next call (it may point
  // into this object). Needs Buffer::kOwn.
  const SensorFrame& apply(const SensorFrame& frame);
  // The same into the caller's buffer (colour's size): out points into it, or passes through
  // when nothing is moved.
  void apply_into(const SensorFrame& frame, uint16_t* depth, SensorFrame* out);
  // The last apply()'s result.
  const SensorFrame& last() const { return frame_; }
  // Bytes init allocates for these params.
  static size_t bytes_needed(const Params& params, Buffer buffer = Buffer::kOwn);

 private:
  bool on_ = false;
  int depth_width_px_ = 0, depth_height_px_ = 0;  // as the sensor delivers it
  int colour_width_px_ = 0, colour_height_px_ = 0;
  DepthRegistration registration_;
  ImageU16 registered_;
  SensorFrame frame_;
};

}  // namespace rgbdtam

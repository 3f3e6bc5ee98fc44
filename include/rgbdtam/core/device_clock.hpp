#pragma once
// A camera's own clock carried over to the host's. A UVC camera stamps each frame with its clock
// at capture (the payload header's PTS); the host stamps it on arrival, late by the transfer,
// which varies with USB traffic by milliseconds. Over a window of frames the smallest
// arrival-minus-capture difference is the transfer without waiting; capture time plus that
// difference keeps the host's clock and meaning but none of the transfer's jitter, and frames of
// two streams of one camera (depth and colour) are compared on the camera's own clock.

#include <cstdint>

namespace rgbdtam {

class DeviceClock {
 public:
  static constexpr int kWindow = 64;            // frames the smallest difference is taken over
  static constexpr double kMaxStepBackS = 1.0;  // further back: the camera's clock restarted
  // ticks_per_s: the camera clock's rate (a RealSense D4xx counts microseconds).
  void reset(double ticks_per_s);
  // A frame stamped `ticks` by the camera (32 bits, wrapping) that the host stamped arrival_ns:
  // its stamp on the host's clock. A camera clock that runs back by more than kMaxStepBackS
  // (the camera was reset) starts the clock again.
  int64_t to_host_ns(uint32_t ticks, int64_t arrival_ns);
  bool running() const { return count_ > 0; }

 private:
  void restart();  // the window and the unwrapped time cleared; the rate kept
  double ns_per_tick_ = 1000.0;
  uint32_t last_ticks_ = 0;
  int64_t device_ns_ = 0;  // the camera's time since the first frame, unwrapped
  int64_t differences_[kWindow] = {};
  int count_ = 0, next_ = 0;
};

}  // namespace rgbdtam

#include "rgbdtam/core/device_clock.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdtam {

void DeviceClock::reset(double ticks_per_s) {
  ns_per_tick_ = 1e9 / ticks_per_s;
  restart();
}

void DeviceClock::restart() {
  count_ = next_ = 0;
  device_ns_ = 0;
}

int64_t DeviceClock::to_host_ns(uint32_t ticks, int64_t arrival_ns) {
  // Modulo 2^32, so a wrap is a step forward; two streams' frames interleave, so a step back
  // within kMaxStepBackS is one stream's frame captured before the other's.
  const double step_ns =
      static_cast<double>(static_cast<int32_t>(ticks - last_ticks_)) * ns_per_tick_;
  if (count_ > 0 && step_ns < -kMaxStepBackS * 1e9) restart();
  if (count_ > 0) device_ns_ += std::llround(step_ns);
  last_ticks_ = ticks;
  differences_[next_] = arrival_ns - device_ns_;
  next_ = (next_ + 1) % kWindow;
  count_ = std::min(count_ + 1, kWindow);
  return device_ns_ + *std::min_element(differences_, differences_ + count_);
}

}  // namespace rgbdtam

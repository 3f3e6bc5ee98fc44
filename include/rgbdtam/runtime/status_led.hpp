#pragma once
// The status LED's blink pattern and the frame trigger pulse, written through GpioOutputs
// (port/gpio_outputs.hpp), which hal implements.

#include <cstdint>

#include "rgbdtam/port/gpio_outputs.hpp"

namespace rgbdtam {

// What the LED shows, most severe first.
enum class LedState : uint8_t {
  kFault,         // a sensor error in the last 2 s: double flash every second
  kLost,          // tracking lost: 5 Hz blink
  kInitialising,  // no keyframe yet: 1 Hz blink
  kTracking,      // steady on
};

// Blink patterns as a pure function of state and time, so tests need no clock.
bool led_is_on(LedState state, int64_t now_ns);

// Drives the LED line from the tracker's thread: writes the line only when it changes.
class StatusLed {
 public:
  void init(GpioOutputs* gpio, int line) {
    gpio_ = gpio;
    line_ = line;
  }
  void update(LedState state, int64_t now_ns);
  uint32_t transitions() const { return transitions_; }
  // How many updates showed this state (what an operator could have seen, whatever the blink
  // phase at those moments).
  uint32_t updates_in(LedState state) const { return updates_[static_cast<int>(state)]; }

 private:
  GpioOutputs* gpio_ = nullptr;
  int line_ = -1;
  bool on_ = false;
  bool written_ = false;
  uint32_t transitions_ = 0;
  uint32_t updates_[4] = {};
};

}  // namespace rgbdtam

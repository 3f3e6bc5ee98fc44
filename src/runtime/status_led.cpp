#include "rgbdtam/runtime/status_led.hpp"

namespace rgbdtam {

bool led_is_on(LedState state, int64_t now_ns) {
  constexpr int64_t kMs = 1000000;
  const int64_t t_ms = (now_ns / kMs) % 1000;  // position in the current second
  switch (state) {
    case LedState::kTracking:
      return true;
    case LedState::kInitialising:
      return t_ms < 500;
    case LedState::kLost:
      return t_ms % 200 < 100;
    case LedState::kFault:
      return t_ms < 100 || (t_ms >= 200 && t_ms < 300);
  }
  return false;
}

void StatusLed::update(LedState state, int64_t now_ns) {
  if (gpio_ == nullptr || line_ < 0) return;
  ++updates_[static_cast<int>(state)];
  const bool on = led_is_on(state, now_ns);
  if (written_ && on == on_) return;
  gpio_->set(line_, on);
  transitions_ += written_ ? 1 : 0;
  on_ = on;
  written_ = true;
}

}  // namespace rgbdtam

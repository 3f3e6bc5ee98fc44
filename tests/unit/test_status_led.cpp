// The status LED's blink patterns, and that the line is written only when it changes.
#include <gtest/gtest.h>

#include <string>

#include "measures.hpp"
#include "rgbdtam/hal/gpio.hpp"
#include "rgbdtam/runtime/status_led.hpp"

namespace rgbdtam {
namespace {

using testing::kMs;

// The fraction of one second the LED is on, sampled every millisecond.
double duty(LedState s) {
  int on = 0;
  for (int t = 0; t < 1000; ++t) on += led_is_on(s, 7000 * kMs + t * kMs) ? 1 : 0;
  return on / 1000.0;
}

int flashes_per_second(LedState s) {
  int rising = 0;
  bool was = led_is_on(s, 7000 * kMs - kMs);
  for (int t = 0; t < 1000; ++t) {
    const bool on = led_is_on(s, 7000 * kMs + t * kMs);
    rising += on && !was;
    was = on;
  }
  return rising;
}

TEST(StatusLed, EachStateHasItsOwnPattern) {
  EXPECT_EQ(duty(LedState::kTracking), 1.0);
  EXPECT_EQ(flashes_per_second(LedState::kInitialising), 1);
  EXPECT_DOUBLE_EQ(duty(LedState::kInitialising), 0.5);
  EXPECT_EQ(flashes_per_second(LedState::kLost), 5);
  EXPECT_EQ(flashes_per_second(LedState::kFault), 2);
  EXPECT_DOUBLE_EQ(duty(LedState::kFault), 0.2);
}

TEST(StatusLed, WritesTheLineOnlyWhenItChanges) {
  FakeGpio gpio;
  StatusLed led;
  led.init(&gpio, 17);
  for (int frame = 0; frame < 90; ++frame) led.update(LedState::kTracking, frame * 33 * kMs);
  EXPECT_EQ(gpio.writes(17), 1u);
  EXPECT_TRUE(gpio.level(17));
  // Lost for 3 s at 30 Hz: the 5 Hz blink is sampled at the frame rate.
  for (int frame = 0; frame < 90; ++frame) led.update(LedState::kLost, frame * 33 * kMs);
  EXPECT_GE(gpio.rising_edges(17), 14u);
  EXPECT_EQ(led.transitions() + 1, gpio.writes(17));
  StatusLed none;  // no LED line on this board: nothing is written
  none.init(&gpio, -1);
  none.update(LedState::kLost, 0);
  EXPECT_EQ(led.transitions() + 1, gpio.writes(17));
}

TEST(Gpio, AMissingChipIsAClearError) {
  LibgpiodOutputs chip;
  const int lines[] = {17, -1};
  const Status s = chip.open("/dev/gpiochip-missing", lines, 2);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("/dev/gpiochip-missing"), std::string::npos);
  chip.set(17, true);  // nothing was requested: a no-op, not a crash
  EXPECT_EQ(chip.errors(), 0u);
}

}  // namespace
}  // namespace rgbdtam

// Hardware-in-the-loop tests: they run on a board with its hardware attached, through
// tools/hil/run.py, which names the board (RGBDTAM_HIL_BOARD: its folder) and what its rack
// provides (RGBDTAM_HIL_ATTACHED, e.g. "sensor,serial-loopback"; RGBDTAM_HIL_GPIO_INPUT and
// RGBDTAM_HIL_SERIAL_LOOPBACK for the wiring). Each skips, naming what it needs, when that is not
// attached; board/<name>/hil.manifest says what a pass means.
#include <gpiod.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include "config_files.hpp"
#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/serial_link.hpp"
#include "rgbdtam/runtime/mavlink.hpp"
#include "rgbdtam/runtime/pose_link.hpp"
#include "run_job.hpp"

namespace rgbdtam {
namespace {

bool attached(const char* hardware) {
  const char* list = std::getenv("RGBDTAM_HIL_ATTACHED");
  if (list == nullptr) return false;
  const std::string padded = std::string(",") + list + ",";
  return padded.find(std::string(",") + hardware + ",") != std::string::npos;
}

#define RGBDTAM_NEEDS(hardware)                                                 \
  if (!attached(hardware)) GTEST_SKIP() << "needs " hardware " (not attached)"; \
  Board board;                                                                  \
  const char* board_dir = std::getenv("RGBDTAM_HIL_BOARD");                     \
  ASSERT_NE(board_dir, nullptr) << "RGBDTAM_HIL_BOARD names the board folder";  \
  ASSERT_TRUE(load_board(board_dir, &board).is_ok())

int env_int(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::atoi(v) : -1;
}

TEST(Hardware, TheBoardsSensorDeliversPairedFramesWithDepth) {
  RGBDTAM_NEEDS("sensor");
  RunOptions options;
  options.board_dir = board_dir;
  Params params;
  ASSERT_TRUE(load_board_and_params(options, &board, &params).is_ok());
  BoardSensor sensor;
  const Status opened = open_board_sensor(board, params, &sensor);
  ASSERT_TRUE(opened.is_ok()) << opened.message();
  ASSERT_TRUE(sensor.live->start(ThreadPlacement()).is_ok());
  const int64_t start = monotonic_ns();
  int frames = 0;
  double valid_fraction = 0;
  while (frames < 30 && monotonic_ns() - start < 3'000'000'000) {
    SensorFrame f;
    Status warning;
    if (!sensor.live->next(&f, &warning).is_ok()) continue;
    ++frames;
    int valid = 0;
    const int n = f.width_px * f.height_px;
    for (int i = 0; i < n; ++i) valid += f.depth[i] != 0;
    valid_fraction = static_cast<double>(valid) / n;
  }
  sensor.live->stop();
  EXPECT_EQ(frames, 30) << "30 frames within 3 s";
  EXPECT_GE(valid_fraction, 0.3) << "depth on at least 30 % of the last frame";
}

TEST(Hardware, TheLedLineLoopedBackToAnInputReadsWhatItWrites) {
  RGBDTAM_NEEDS("gpio-loopback");
  const int input = env_int("RGBDTAM_HIL_GPIO_INPUT");
  ASSERT_GE(input, 0) << "RGBDTAM_HIL_GPIO_INPUT names the input the LED line is wired to";
  LibgpiodOutputs outputs;
  const int lines[] = {board.gpio_led_line};
  ASSERT_TRUE(outputs.open(board.gpio_chip, lines, 1).is_ok());
  gpiod_chip* chip = gpiod_chip_open(board.gpio_chip);
  ASSERT_NE(chip, nullptr);
  gpiod_line* line = gpiod_chip_get_line(chip, static_cast<unsigned>(input));
  ASSERT_NE(line, nullptr);
  ASSERT_EQ(gpiod_line_request_input(line, "rgbdtam-hil"), 0);
  int mismatches = 0;
  for (int i = 0; i < 20; ++i) {
    const bool on = i % 2 == 0;
    outputs.set(board.gpio_led_line, on);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    mismatches += gpiod_line_get_value(line) != (on ? 1 : 0);
  }
  gpiod_chip_close(chip);
  EXPECT_EQ(mismatches, 0);
}

TEST(Hardware, ASerialLoopbackCarriesMavlinkIntact) {
  RGBDTAM_NEEDS("serial-loopback");
  const char* device = std::getenv("RGBDTAM_HIL_SERIAL_LOOPBACK");
  SerialLink port;
  const Status opened =
      port.open(device != nullptr ? device : board.link_serial_device, board.link_baud);
  ASSERT_TRUE(opened.is_ok()) << opened.message();
  PoseLinkConfig config;
  PoseLink link;
  link.init(config, &port);
  mavlink::Decoder decoder;
  int received = 0;
  uint8_t bytes[512];
  for (int i = 0; i < 100; ++i) {
    link.on_status(mavlink::kMavSeverityInfo, "rgbdtam hil loopback", monotonic_ns());
    for (int k = 0; k < 10 && port.flush() > 0; ++k)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const int64_t until = monotonic_ns() + 50'000'000;
    while (monotonic_ns() < until) {
      const size_t n = port.receive(bytes, sizeof(bytes));
      decoder.feed_all(bytes, n, [&](const mavlink::Frame&) { ++received; });
    }
  }
  EXPECT_EQ(received, 100);
  EXPECT_EQ(decoder.counters().crc_errors, 0u);
}

TEST(Hardware, TheFlightControllerOnTheBoardsPortIsHeardAndAnswersTimesync) {
  RGBDTAM_NEEDS("flight-controller");
  SerialLink port;
  const Status opened = port.open(board.link_serial_device, board.link_baud);
  ASSERT_TRUE(opened.is_ok()) << opened.message();
  PoseLinkConfig config;
  config.system_id = board.link_system_id;
  config.component_id = board.link_component_id;
  PoseLink link;
  link.init(config, &port);
  const int64_t start = monotonic_ns();
  while (monotonic_ns() - start < 5'000'000'000 && link.peer().timesync_replies == 0) {
    link.tick(monotonic_ns(), mavlink::kMavStateActive);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(link.peer().heard) << "no HEARTBEAT from an autopilot in 5 s";
  EXPECT_GT(link.peer().timesync_replies, 0u) << "no answer to TIMESYNC in 5 s";
}

}  // namespace
}  // namespace rgbdtam

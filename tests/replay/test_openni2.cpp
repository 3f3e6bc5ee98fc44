// The OpenNI2 backend against OpenNI2's own "Dummy" device (Debian's libopenni2 ships it): a
// 320x240 depth + RGB device with a fixed test pattern at 30 Hz. What the backend delivers is
// compared, pixel for pixel, with the frames an independent OpenNI2 reader sees.
#include <OpenNI.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "rgbdtam/hal/openni2_source.hpp"
#include "run_job.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

constexpr int kW = 320, kH = 240;
constexpr int64_t kMs = 1'000'000;

// The Dummy device draws a moving pattern that depends only on the frame's index, and stamps
// frame i at i x 33 ms: frames read straight from OpenNI2, by timestamp (microseconds).
struct RawFrames {
  std::map<uint64_t, std::vector<uint16_t>> depth;
  std::map<uint64_t, std::vector<uint8_t>> rgb;
};

// Reads frames up to last_us; a reader can miss a frame (OpenNI2 keeps only the newest), so
// the device is opened again, from frame 1, until every wanted frame was seen.
void read_raw_dummy_once(uint64_t last_us, RawFrames* raw);

RawFrames read_raw_dummy(const std::vector<uint64_t>& wanted_us) {
  RawFrames raw;
  auto missing = [&] {
    for (uint64_t us : wanted_us)
      if (raw.depth.count(us) == 0 || raw.rgb.count(us) == 0) return true;
    return false;
  };
  for (int attempt = 0; attempt < 20 && missing(); ++attempt) {
    read_raw_dummy_once(wanted_us.back(), &raw);
  }
  return raw;
}

void read_raw_dummy_once(uint64_t last_us, RawFrames* out) {
  RawFrames& raw = *out;
  EXPECT_EQ(openni::OpenNI::initialize(), openni::STATUS_OK);
  openni::Device device;
  EXPECT_EQ(device.open("Dummy"), openni::STATUS_OK);
  openni::VideoStream depth, colour;
  EXPECT_EQ(depth.create(device, openni::SENSOR_DEPTH), openni::STATUS_OK);
  EXPECT_EQ(colour.create(device, openni::SENSOR_COLOR), openni::STATUS_OK);
  depth.start();
  colour.start();
  openni::VideoStream* streams[2] = {&depth, &colour};
  for (bool done[2] = {false, false}; !done[0] || !done[1];) {
    int ready = -1;
    if (openni::OpenNI::waitForAnyStream(streams, 2, &ready, 2000) != openni::STATUS_OK) break;
    openni::VideoFrameRef f;
    streams[ready]->readFrame(&f);
    done[ready] = f.getTimestamp() >= last_us;
    const auto* data = static_cast<const uint8_t*>(f.getData());
    if (ready == 0) {
      const auto* mm = reinterpret_cast<const uint16_t*>(data);
      raw.depth[f.getTimestamp()].assign(mm, mm + kW * kH);
    } else {
      raw.rgb[f.getTimestamp()].assign(data, data + kW * kH * 3);
    }
  }
  depth.stop();
  colour.stop();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // see OpenNi2Source::close()
  depth.destroy();
  colour.destroy();
  device.close();
}

TEST(OpenNi2, DummyFramesArriveAsTheDeviceGivesThem) {
  OpenNi2Source source;
  const Status s = source.open("Dummy", kW, kH, 30, 10 * kMs, 1000);
  ASSERT_TRUE(s.is_ok()) << s.message();
  std::vector<std::vector<uint16_t>> depth;
  std::vector<std::vector<uint8_t>> gray;
  std::vector<int64_t> stamps_ns;
  for (int i = 0; i < 5; ++i) {
    SensorFrame f;
    Status warning;
    const Status n = source.next(&f, &warning);
    ASSERT_TRUE(n.is_ok()) << n.message();
    EXPECT_EQ(f.sequence, static_cast<uint32_t>(i));
    EXPECT_EQ(f.width_px, kW);
    EXPECT_EQ(f.depth_timestamp_ns, f.timestamp_ns) << "a synchronised pair";
    stamps_ns.push_back(f.timestamp_ns);
    depth.emplace_back(f.depth, f.depth + kW * kH);
    gray.emplace_back(f.gray, f.gray + kW * kH);
  }
  // Frames come 33 ms apart on the device's clock; any the backend missed are counted.
  const int64_t span_frames = (stamps_ns.back() - stamps_ns.front()) / (33 * kMs);
  EXPECT_EQ(stamps_ns.back() - stamps_ns.front(), span_frames * 33 * kMs);
  EXPECT_EQ(static_cast<int64_t>(source.dropped()), span_frames - 4);
  // The Dummy device has no registration; it says so rather than pretending.
  EXPECT_FALSE(source.capabilities().registered);
  source.close();

  std::vector<uint64_t> wanted_us;
  for (int64_t ns : stamps_ns) wanted_us.push_back(static_cast<uint64_t>(ns / 1000));
  const RawFrames raw = read_raw_dummy(wanted_us);
  for (size_t i = 0; i < stamps_ns.size(); ++i) {
    const uint64_t us = wanted_us[i];
    ASSERT_TRUE(raw.depth.count(us) == 1 && raw.rgb.count(us) == 1) << us;
    std::vector<uint8_t> want_gray(kW * kH);
    rgb_to_gray(raw.rgb.at(us).data(), want_gray.data(), kW * kH);
    EXPECT_EQ(depth[i], raw.depth.at(us)) << "millimetres as the device gives them, frame " << i;
    EXPECT_EQ(gray[i], want_gray) << "BT.601 grey of the device's RGB, frame " << i;
  }
}

TEST(OpenNi2, AModeTheDeviceLacksAndAMissingDeviceAreClearErrors) {
  OpenNi2Source source;
  Status s = source.open("Dummy", 640, 480, 30, 10 * kMs, 1000);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(
      std::string(s.message()).find("no depth (mm) mode 640x480 at 30 Hz; it offers 320x240@30"),
      std::string::npos)
      << s.message();
  OpenNi2Source missing;
  s = missing.open("/dev/no-such-sensor", kW, kH, 30, 10 * kMs, 1000);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("cannot open '/dev/no-such-sensor'"), std::string::npos)
      << s.message();
}

TEST(OpenNi2, AReopenedDeviceDeliversFramesAgain) {
  OpenNi2Source source;
  ASSERT_TRUE(source.open("Dummy", kW, kH, 30, 10 * kMs, 1000).is_ok());
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(source.next(&f, &warning).is_ok());
  const Status r = source.reopen();
  ASSERT_TRUE(r.is_ok()) << r.message();
  const Status n = source.next(&f, &warning);
  ASSERT_TRUE(n.is_ok()) << n.message();
  EXPECT_EQ(f.sequence, 1u);
}

TEST(OpenNi2, TheFirmwareRunsOnTheDummyDevice) {
  // The host-emulation board with its sensor swapped for the Dummy device, at its size.
  const std::string dir = testing::make_temp_dir("openni2_run");
  const std::string config = dir + "/dummy.conf";
  ASSERT_TRUE(testing::write_text(config,
                                  "camera.width = 320\ncamera.height = 240\ncamera.fx = 262.5\n"
                                  "camera.fy = 262.5\ncamera.cx = 159.5\ncamera.cy = 119.5\n"
                                  "depth.factor = 1000\n"));
  const std::string board = testing::source_path("board/host-emulation");
  const std::string config_override = "sensor.config=" + config;
  RunOptions options;
  options.board_dir = board.c_str();
  options.board_overrides[options.board_override_count++] = "sensor.kind=openni2";
  options.board_overrides[options.board_override_count++] = "sensor.device=Dummy";
  options.board_overrides[options.board_override_count++] = config_override.c_str();
  options.max_frames = 20;
  options.progress = false;
  RunJob job;
  const Status s = job.init(options);
  ASSERT_TRUE(s.is_ok()) << s.message();
  ASSERT_TRUE(job.start().is_ok());
  while (job.step()) {
  }
  job.finish();
  const FirmwareCounters& c = job.runtime().counters();
  EXPECT_EQ(c.frames, 20u);
  EXPECT_EQ(c.sensor_errors, 0u);
  EXPECT_GE(job.link().counters().tx_frames, 20u) << "a pose (or its loss) for every frame";
}

}  // namespace
}  // namespace rgbdtam

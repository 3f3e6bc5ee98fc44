// The V4L2 backend against a scripted fake device: format negotiation and refusal, mmap
// buffers, timestamps, depth/colour pairing, EINTR/EAGAIN, buffers flagged as errors and a
// device unplugged mid-stream. Every scenario ends in frames or a clear error, never a hang.
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "fake_usb.hpp"
#include "fake_v4l2.hpp"
#include "rgbdtam/hal/sensor_recovery.hpp"
#include "rgbdtam/hal/v4l2_nodes.hpp"
#include "rgbdtam/hal/v4l2_source.hpp"
#include "rgbdtam/runtime/registering_sensor.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

using testing::Event;
using testing::FakeV4l2;
using testing::frame;
using testing::kH;
using testing::kMs;
using testing::kW;

struct Rig {
  FakeV4l2 io;
  FakeV4l2::Node* depth;
  FakeV4l2::Node* colour;
  V4l2Source source;
  V4l2Colour colour_format;
  explicit Rig(uint32_t depth_fourcc = V4L2_PIX_FMT_Z16, V4l2Colour colour_as = V4l2Colour::kYuyv)
      : colour_format(colour_as) {
    io.nodes.reserve(2);
    depth = &io.add("/dev/video0", depth_fourcc);
    colour = &io.add("/dev/video1",
                     colour_as == V4l2Colour::kMjpeg ? V4L2_PIX_FMT_MJPEG : V4L2_PIX_FMT_YUYV);
    io.now_ns = 900 * kMs;  // the scripts start about a second in
  }
  Status open() {
    return source.open(&io, "/dev/video0", "/dev/video1", same_size(kW, kH), 10 * kMs, 500,
                       colour_format);
  }
};

// A kW x kH grey pattern: a ramp, brighter with `level`.
std::vector<uint8_t> pattern(int level) {
  std::vector<uint8_t> g(kW * kH);
  for (int i = 0; i < kW * kH; ++i) g[i] = static_cast<uint8_t>(40 + 10 * level + 8 * (i % kW));
  return g;
}

TEST(JpegArena, FreedBlocksReturnFromTheTopAndTheArenaRefusesWhatDoesNotFit) {
  JpegArena arena;
  arena.allocate(1024);
  void* a = arena.get(100);
  const size_t after_a = arena.used_bytes();
  void* b = arena.get(100);
  void* c = arena.get(100);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(b) % 16, 0u);
  const size_t top = arena.used_bytes();
  arena.put(b);  // below c: kept until c goes
  EXPECT_EQ(arena.used_bytes(), top);
  arena.put(c);
  EXPECT_EQ(arena.used_bytes(), after_a) << "b and c both returned";
  EXPECT_EQ(arena.get(2000), nullptr);
  arena.put(a);
  EXPECT_EQ(arena.used_bytes(), 0u);
  EXPECT_EQ(arena.peak_bytes(), top);
}

TEST(V4l2Mjpeg, ColourFramesAreDecodedToTheirLuma) {
  Rig rig(V4L2_PIX_FMT_Z16, V4l2Colour::kMjpeg);
  for (int level = 0; level < 3; ++level) {
    rig.colour->jpeg.push_back(testing::encode_jpeg(pattern(level).data(), kW, kH, 95));
  }
  ASSERT_TRUE(rig.open().is_ok());
  for (int i = 0; i < 3; ++i) {
    rig.depth->script.push_back(frame(1000 + 33 * i, static_cast<uint8_t>(i)));
    rig.colour->script.push_back(frame(1001 + 33 * i, static_cast<uint8_t>(i)));
  }
  size_t arena_top = 0;
  for (int i = 0; i < 3; ++i) {
    SensorFrame f;
    Status warning;
    const Status s = rig.source.next(&f, &warning);
    ASSERT_TRUE(s.is_ok()) << s.message();
    const std::vector<uint8_t> want = pattern(i);
    int worst = 0;
    for (int p = 0; p < kW * kH; ++p) worst = std::max(worst, std::abs(f.gray[p] - want[p]));
    EXPECT_LE(worst, 3) << "frame " << i << ": JPEG at quality 95";
    EXPECT_EQ(f.depth[5], i * 100 + 5);
    // Every frame leaves libjpeg's arena where the one before left it.
    if (i == 1) {
      arena_top = rig.source.jpeg().arena().used_bytes();
    } else if (i == 2) {
      EXPECT_EQ(rig.source.jpeg().arena().used_bytes(), arena_top);
    }
  }
  EXPECT_EQ(rig.source.jpeg().decoded(), 3u);
}

TEST(V4l2Mjpeg, ACorruptTruncatedOrMissizedJpegIsAnErrorAndTheNextFrameDecodes) {
  Rig rig(V4L2_PIX_FMT_Z16, V4l2Colour::kMjpeg);
  const std::vector<uint8_t> good = testing::encode_jpeg(pattern(0).data(), kW, kH, 90);
  std::vector<uint8_t> truncated(good.begin(), good.begin() + good.size() / 2);
  std::vector<uint8_t> garbage(good.size());
  for (size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<uint8_t>(i * 37);
  std::vector<uint8_t> wide(2 * kW * kH, 90);
  rig.colour->jpeg = {good, truncated, garbage, testing::encode_jpeg(wide.data(), 2 * kW, kH, 90)};
  ASSERT_TRUE(rig.open().is_ok());
  for (int i = 0; i < 5; ++i) {
    rig.depth->script.push_back(frame(1000 + 33 * i, 0));
    rig.colour->script.push_back(frame(1001 + 33 * i, static_cast<uint8_t>(i % 4)));
  }
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(rig.source.next(&f, &warning).is_ok());
  const size_t top = rig.source.jpeg().arena().used_bytes();
  for (const char* want : {"corrupt JPEG", "corrupt JPEG", "32x8, not 16x8"}) {
    const Status s = rig.source.next(&f, &warning);
    ASSERT_FALSE(s.is_ok());
    EXPECT_NE(std::string(s.message()).find(want), std::string::npos) << s.message();
    EXPECT_EQ(rig.source.jpeg().arena().used_bytes(), top) << "the failed frame's memory is back";
  }
  const Status again = rig.source.next(&f, &warning);
  EXPECT_TRUE(again.is_ok()) << again.message();
  EXPECT_EQ(rig.depth->queued.size(), 3u) << "every buffer went back to the driver";
}

TEST(V4l2, DeliversPairedFramesWithTheirValuesAndTimestamps) {
  Rig rig;
  ASSERT_TRUE(rig.open().is_ok());
  for (int i = 0; i < 3; ++i) {
    rig.depth->script.push_back(frame(1000 + 33 * i, static_cast<uint8_t>(10 + i)));
    rig.colour->script.push_back(frame(1001 + 33 * i, static_cast<uint8_t>(50 + i)));
  }
  for (int i = 0; i < 3; ++i) {
    SensorFrame f;
    Status warning;
    ASSERT_TRUE(rig.source.next(&f, &warning).is_ok()) << i;
    EXPECT_EQ(f.timestamp_ns, (1001 + 33 * i) * kMs);
    EXPECT_EQ(f.depth_timestamp_ns, (1000 + 33 * i) * kMs);
    EXPECT_EQ(f.gray[0], 50 + i);
    EXPECT_EQ(f.gray[1], 51 + i);  // the second pixel's own Y, not U or V
    EXPECT_EQ(f.depth[5], (10 + i) * 100 + 5);
  }
  EXPECT_EQ(rig.source.counters().delivered, 3u);
  EXPECT_EQ(rig.depth->queued.size(), 3u) << "every buffer went back to the driver";
}

TEST(V4l2, EintrAndEagainAreRetried) {
  Rig rig;
  ASSERT_TRUE(rig.open().is_ok());
  rig.depth->script = {{Event::kEintr}, {Event::kEagain}, frame(1000, 1)};
  rig.colour->script = {{Event::kEagain}, frame(1002, 2)};
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(rig.source.next(&f, &warning).is_ok());
  EXPECT_EQ(rig.source.counters().retries, 3u);
}

TEST(V4l2, BuffersFlaggedAsErrorsAreSkippedAndRequeued) {
  Rig rig;
  ASSERT_TRUE(rig.open().is_ok());
  rig.depth->script = {{Event::kErrorFlag, 990 * kMs, 0}, frame(1000, 7)};
  rig.colour->script = {frame(1000, 9)};
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(rig.source.next(&f, &warning).is_ok());
  EXPECT_EQ(f.depth[0], 700);
  EXPECT_EQ(rig.source.counters().error_buffers, 1u);
  EXPECT_EQ(rig.depth->queued.size(), 3u);
}

TEST(V4l2, UnpairedFramesAreLetGo) {
  Rig rig;
  ASSERT_TRUE(rig.open().is_ok());
  rig.depth->script = {frame(1000, 1), frame(1066, 3)};
  rig.colour->script = {frame(1067, 4)};
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(rig.source.next(&f, &warning).is_ok());
  EXPECT_EQ(f.depth_timestamp_ns, 1066 * kMs);
  EXPECT_EQ(rig.source.counters().unpaired, 1u);
}

TEST(V4l2, WhenTheTrackerFallsBehindTheNewestFrameIsKept) {
  Rig rig;
  ASSERT_TRUE(rig.open().is_ok());
  for (int i = 0; i < 3; ++i) {
    rig.depth->script.push_back(frame(1000 + 33 * i, static_cast<uint8_t>(10 + i)));
    rig.colour->script.push_back(frame(1000 + 33 * i, static_cast<uint8_t>(50 + i)));
  }
  rig.io.now_ns = 1100 * kMs;  // all three pairs arrived while the tracker was busy
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(rig.source.next(&f, &warning).is_ok());
  EXPECT_EQ(f.timestamp_ns, 1066 * kMs);
  EXPECT_EQ(f.gray[0], 52);
  EXPECT_EQ(rig.source.dropped(), 4u);  // two older frames on each node
  EXPECT_EQ(rig.depth->queued.size(), 3u) << "overtaken buffers went back to the driver";
  EXPECT_EQ(rig.colour->queued.size(), 3u);
}

TEST(V4l2, ARefusedFormatIsAClearError) {
  Rig rig(V4L2_PIX_FMT_YUYV);  // the "depth" node has no Z16
  const Status s = rig.open();
  ASSERT_FALSE(s.is_ok());
  const std::string m = s.message();
  EXPECT_NE(m.find("/dev/video0"), std::string::npos) << m;
  EXPECT_NE(m.find("Z16"), std::string::npos) << m;
  EXPECT_NE(m.find("offers YUYV"), std::string::npos) << m;
}

TEST(V4l2, ADepthCameraOfItsOwnSizeIsStreamedAtItAndAnotherSizeNamesWhatItOffers) {
  // A D435's depth node streams 848x480 beside colour's 640x480: here 24x12 beside 16x8.
  constexpr int kDepthW = 24, kDepthH = 12;
  Rig as_colour, rig;
  for (Rig* r : {&as_colour, &rig}) {
    r->depth->width = kDepthW;
    r->depth->height = kDepthH;
  }
  const Status same = as_colour.open();  // depth asked for at colour's size
  ASSERT_FALSE(same.is_ok());
  EXPECT_NE(std::string(same.message()).find("offers Z16  24x12"), std::string::npos)
      << same.message();
  ASSERT_TRUE(
      rig.source
          .open(&rig.io, "/dev/video0", "/dev/video1", {kW, kH, kDepthW, kDepthH}, 10 * kMs, 500)
          .is_ok());
  rig.depth->script.push_back(frame(1000, 3));
  rig.colour->script.push_back(frame(1001, 50));
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(rig.source.next(&f, &warning).is_ok());
  EXPECT_EQ(f.width_px, kW);
  EXPECT_EQ(f.height_px, kH);
  EXPECT_EQ(f.depth_width_px, kDepthW);
  EXPECT_EQ(f.depth_height_px, kDepthH);
  EXPECT_EQ(f.depth[kDepthW * kDepthH - 1], 3 * 100 + kDepthW * kDepthH - 1) << "every row copied";
  EXPECT_EQ(f.gray[kW * kH - 1], 51);
}

// V4L2 lets a driver pad each row (bytesperline beyond the pixels' bytes); uvcvideo packs them,
// other drivers may not. Rows are read where the driver says they start, the padding never.
TEST(V4l2, RowsThatTheDriverPadsAreReadRowByRow) {
  Rig rig;
  rig.depth->row_padding_bytes = 12;
  rig.colour->row_padding_bytes = 6;
  ASSERT_TRUE(rig.open().is_ok());
  rig.depth->script.push_back(frame(1000, 3));
  rig.colour->script.push_back(frame(1001, 50));
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(rig.source.next(&f, &warning).is_ok());
  for (int i = 0; i < kW * kH; ++i) {
    ASSERT_EQ(f.depth[i], 3 * 100 + i) << "depth pixel " << i;
    ASSERT_EQ(f.gray[i], 50 + i % 2) << "colour pixel " << i;
  }
}

TEST(V4l2, RowsShorterThanTheirPixelsAreRefused) {
  struct ShortRows : FakeV4l2 {
    int ioctl(int fd, unsigned long request, void* arg) override {
      const int r = FakeV4l2::ioctl(fd, request, arg);
      if (request == VIDIOC_S_FMT) static_cast<v4l2_format*>(arg)->fmt.pix.bytesperline = kW;
      return r;
    }
  } io;
  io.add("/dev/video0", V4L2_PIX_FMT_Z16);
  io.add("/dev/video1", V4L2_PIX_FMT_YUYV);
  V4l2Source source;
  const Status s = source.open(&io, "/dev/video0", "/dev/video1", same_size(kW, kH), 10 * kMs, 500);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("rows of 16 bytes are shorter than 16 pixels of Z16"),
            std::string::npos)
      << s.message();
}

// A D435 on a Raspberry Pi 4: its depth moved into colour on the sensor's own thread.
TEST(V4l2, RegistrationOnTheSensorsThreadGivesTheTrackerWhatItWouldHaveMadeAndEveryError) {
  constexpr int kDepthW = 24, kDepthH = 12;
  Params params;
  params.camera = {14.0, 14.0, 7.5, 3.5, kW, kH};
  params.depth_camera.register_to_colour = true;
  params.depth_camera.intrinsics = {19.0, 19.0, 11.5, 5.5, kDepthW, kDepthH};
  params.depth_camera.T_c_d = SE3(Eigen::Quaterniond::Identity(), Vector3d(0.015, 0, 0));
  params.sensor.depth_factor = 1000.0;
  Rig threaded, direct;
  for (Rig* r : {&threaded, &direct}) {
    r->depth->width = kDepthW;
    r->depth->height = kDepthH;
    ASSERT_TRUE(
        r->source
            .open(&r->io, "/dev/video0", "/dev/video1", {kW, kH, kDepthW, kDepthH}, 10 * kMs, 500)
            .is_ok());
    for (int i = 0; i < 6; ++i) {
      r->depth->script.push_back(frame(1000 + 33 * i, static_cast<uint8_t>(3 + i)));
      r->colour->script.push_back(frame(1001 + 33 * i, static_cast<uint8_t>(50 + i)));
    }
    r->depth->script.push_back({Event::kUnplug, 1300 * kMs});
  }
  RegisteringSensor sensor;
  sensor.init(&threaded.source, params);
  sensor.hold_every_frame();
  ASSERT_TRUE(sensor.start(ThreadPlacement{}).is_ok());
  DepthInColour on_the_trackers_thread;
  on_the_trackers_thread.init(params);
  SensorFrame f;
  Status warning;
  for (int i = 0; i < 3; ++i) {
    SensorFrame raw;
    ASSERT_TRUE(sensor.next(&f, &warning).is_ok()) << i;
    ASSERT_TRUE(direct.source.next(&raw, &warning).is_ok()) << i;
    const SensorFrame& want = on_the_trackers_thread.apply(raw);
    EXPECT_EQ(f.timestamp_ns, want.timestamp_ns);
    EXPECT_EQ(f.depth_width_px, kW);
    EXPECT_EQ(f.depth_height_px, kH);
    EXPECT_TRUE(std::equal(f.gray, f.gray + kW * kH, want.gray)) << i;
    EXPECT_TRUE(std::equal(f.depth, f.depth + kW * kH, want.depth)) << i;
    EXPECT_GT(std::count_if(f.depth, f.depth + kW * kH, [](uint16_t d) { return d > 0; }), 0);
  }
  // A reopen, as the stall recovery makes it: the thread pauses, the device opens again, and
  // frames flow on (what the thread held when it paused is let go, as the device's own are).
  const int64_t before_ns = f.timestamp_ns;
  ASSERT_TRUE(sensor.reopen().is_ok());
  EXPECT_EQ(threaded.depth->opens, 2);
  ASSERT_TRUE(sensor.next(&f, &warning).is_ok());
  EXPECT_GT(f.timestamp_ns, before_ns);
  // Unplugged: every error reaches the tracker in turn (the thread waits for each to be taken,
  // so a dead device cannot spin it), and stopping does not wait for the device.
  int errors = 0;
  for (int k = 0; k < 8 && errors < 3; ++k) {
    const Status s = sensor.next(&f, &warning);
    EXPECT_NE(s.code(), StatusCode::kEndOfStream) << k;
    errors += s.is_ok() ? 0 : 1;
  }
  EXPECT_EQ(errors, 3);
  sensor.stop();
}

TEST(V4l2, AnUnpluggedDeviceEndsInAnErrorNotAHang) {
  Rig rig;
  ASSERT_TRUE(rig.open().is_ok());
  rig.depth->script = {frame(1000, 1), {Event::kUnplug, 1033 * kMs, 0}};
  rig.colour->script = {frame(1000, 2), frame(1033, 3)};
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(rig.source.next(&f, &warning).is_ok());
  for (int i = 0; i < 3; ++i) {
    const Status s = rig.source.next(&f, &warning);
    ASSERT_FALSE(s.is_ok());
    EXPECT_NE(std::string(s.message()).find("unplugged"), std::string::npos) << s.message();
  }
  rig.source.close();
}

TEST(V4l2, NoFramesIsATimeoutAndAMissingNodeIsNamed) {
  Rig rig;
  ASSERT_TRUE(rig.open().is_ok());
  SensorFrame f;
  Status warning;
  const Status s = rig.source.next(&f, &warning);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("no frame for 500 ms"), std::string::npos);
  FakeV4l2 io;
  V4l2Source missing;
  const Status m = missing.open(&io, "/dev/video7", "/dev/video8", same_size(kW, kH), 10 * kMs, 50);
  ASSERT_FALSE(m.is_ok());
  EXPECT_NE(std::string(m.message()).find("/dev/video7"), std::string::npos);
}

// A RealSense D435 (8086:0b07) as uvcvideo presents it: depth (Z16), infrared (GREY, Y8I, Y12I)
// and colour (YUYV) on interfaces of their own, each followed by its metadata node; a webcam
// enumerated before it takes the low numbers.
struct D435Rig {
  FakeV4l2 io;
  std::string sysfs = testing::make_temp_dir("sysfs_d435");
  std::string devfs = testing::make_temp_dir("devfs_d435");
  FakeV4l2::Node* depth = nullptr;
  FakeV4l2::Node* colour = nullptr;
  D435Rig() {
    io.nodes.reserve(8);
    io.now_ns = 900 * kMs;
    EXPECT_TRUE(testing::add_usb_device(sysfs, "1-1", "046d", "0825", 1, 2));
    EXPECT_TRUE(testing::add_usb_device(sysfs, "2-1", "8086", "0b07", 2, 3));
    node("1-1", "1-1:1.0", 0, V4L2_PIX_FMT_YUYV, {V4L2_PIX_FMT_MJPEG});
    node("1-1", "1-1:1.0", 1, 0, {});
    depth = node("2-1", "2-1:1.0", 2, V4L2_PIX_FMT_Z16, {});
    node("2-1", "2-1:1.0", 3, 0, {});
    node("2-1", "2-1:1.1", 4, V4L2_PIX_FMT_GREY,
         {v4l2_fourcc('Y', '8', 'I', ' '), v4l2_fourcc('Y', '1', '2', 'I')});
    node("2-1", "2-1:1.1", 5, 0, {});
    colour = node("2-1", "2-1:1.3", 6, V4L2_PIX_FMT_YUYV, {});
    node("2-1", "2-1:1.3", 7, 0, {});
  }
  // fourcc 0: a metadata node.
  FakeV4l2::Node* node(const char* device, const char* interface, int number, uint32_t fourcc,
                       std::vector<uint32_t> also) {
    EXPECT_TRUE(testing::add_video_node(sysfs, device, interface, number));
    FakeV4l2::Node& n = io.add(devfs + "/video" + std::to_string(number), fourcc);
    n.metadata = fourcc == 0;
    n.also_offers = std::move(also);
    return &n;
  }
};

TEST(V4l2Nodes, AD435sDepthAndColourAreFoundByUsbIdAndWhatTheyOfferNotByNumber) {
  D435Rig rig;
  V4l2NodeFinder finder;
  V4l2Nodes nodes;
  const Status s = finder.find(&rig.io, rig.sysfs.c_str(), rig.devfs.c_str(), {0x8086, 0x0b07},
                               V4L2_PIX_FMT_YUYV, &nodes);
  ASSERT_TRUE(s.is_ok()) << s.message();
  EXPECT_EQ(std::string(nodes.depth), rig.devfs + "/video2");
  EXPECT_EQ(std::string(nodes.colour), rig.devfs + "/video6") << "not the webcam's video0";
  EXPECT_EQ(std::string(nodes.depth_metadata), rig.devfs + "/video3");
  EXPECT_EQ(std::string(nodes.colour_metadata), rig.devfs + "/video7");
  for (const FakeV4l2::Node& n : rig.io.nodes) EXPECT_FALSE(n.open) << n.path << " left open";

  // Frames flow from the nodes found.
  V4l2Source source;
  source.locate_by_usb({0x8086, 0x0b07}, rig.sysfs.c_str(), rig.devfs.c_str());
  ASSERT_TRUE(source.open(&rig.io, "", "", same_size(kW, kH), 10 * kMs, 500).is_ok());
  rig.depth->script = {frame(1000, 1)};
  rig.colour->script = {frame(1003, 2)};
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(source.next(&f, &warning).is_ok());
  EXPECT_EQ(f.depth[0], 100);
  EXPECT_EQ(f.gray[0], 2);
}

TEST(V4l2Nodes, WhatIsMissingIsNamedWithWhatTheCameraOffers) {
  D435Rig rig;
  V4l2NodeFinder finder;
  V4l2Nodes nodes;
  Status s = finder.find(&rig.io, rig.sysfs.c_str(), rig.devfs.c_str(), {0x8086, 0x0b07},
                         V4L2_PIX_FMT_MJPEG, &nodes);
  ASSERT_FALSE(s.is_ok());
  EXPECT_EQ(std::string(s.message()),
            "USB 8086:0b07 has no MJPG node (its nodes: video2 Z16, video3 metadata, video4 GREY "
            "Y8I Y12I, video5 metadata, video6 YUYV, video7 metadata)");
  s = finder.find(&rig.io, rig.sysfs.c_str(), rig.devfs.c_str(), {0x2bc5, 0x0401},
                  V4L2_PIX_FMT_YUYV, &nodes);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("USB 2bc5:0401 has no video node"), std::string::npos)
      << s.message();
}

TEST(V4l2Nodes, AResetThatRenumbersTheNodesIsFollowedAtTheReopen) {
  D435Rig rig;
  V4l2Source source;
  source.locate_by_usb({0x8086, 0x0b07}, rig.sysfs.c_str(), rig.devfs.c_str());
  ASSERT_TRUE(source.open(&rig.io, "", "", same_size(kW, kH), 10 * kMs, 500).is_ok());
  EXPECT_EQ(std::string(source.nodes().depth), rig.devfs + "/video2");
  source.close();
  // Re-enumerated after a reset: the camera's nodes now start at video8.
  const std::string renumbered = testing::make_temp_dir("sysfs_d435_again");
  EXPECT_TRUE(testing::add_usb_device(renumbered, "2-1", "8086", "0b07", 2, 4));
  const int interface_of[] = {0, 0, 1, 1, 3, 3};
  for (int i = 0; i < 6; ++i) {
    EXPECT_TRUE(testing::add_video_node(renumbered, "2-1",
                                        "2-1:1." + std::to_string(interface_of[i]), 8 + i));
    rig.io.nodes[2 + i].path = rig.devfs + "/video" + std::to_string(8 + i);
  }
  V4l2Source again;
  again.locate_by_usb({0x8086, 0x0b07}, renumbered.c_str(), rig.devfs.c_str());
  ASSERT_TRUE(again.open(&rig.io, "", "", same_size(kW, kH), 10 * kMs, 500).is_ok());
  EXPECT_EQ(std::string(again.nodes().depth), rig.devfs + "/video8");
  EXPECT_EQ(std::string(again.nodes().colour), rig.devfs + "/video12");
}

// A D435's depth and colour of one instant reach the host 3-20 ms after capture, unevenly: by
// arrival, pairs drift apart by more than the pairing limit. Its metadata nodes give each frame's
// capture on the camera's clock (microseconds) and the camera's frame counter.
struct CameraClockScript {
  static constexpr int kFrames = 12;
  // Its colour metadata comes flagged as an error (uvcvideo flags it with a bad frame's).
  static constexpr int kFlaggedColourMetadata = 9;
  const int64_t depth_late_ms[kFrames] = {0, 7, 2, 9, 4, 11, 6, 1, 8, 0, 10, 5};
  const int64_t colour_late_ms[kFrames] = {0, 5, 1, 6, 2, 7, 3, 0, 4, 0, 5, 2};
  // Colour is captured at 1000 + 33 k ms, depth 1 ms after it; depth's transfer takes 8 ms at
  // best, colour's 3 ms.
  static int64_t colour_capture_ms(int k) { return 1000 + 33 * k; }
  void play(D435Rig* rig) const {
    FakeV4l2::Node& depth_meta = rig->io.nodes[3];
    FakeV4l2::Node& colour_meta = rig->io.nodes[7];
    depth_meta.meta_format = colour_meta.meta_format = V4L2_META_FMT_D4XX;
    for (int k = 0; k < kFrames; ++k) {
      const int64_t depth_at_ms = colour_capture_ms(k) + 1 + 8 + depth_late_ms[k];
      const int64_t colour_at_ms = colour_capture_ms(k) + 3 + colour_late_ms[k];
      rig->depth->script.push_back(frame(depth_at_ms, static_cast<uint8_t>(k)));
      rig->colour->script.push_back(frame(colour_at_ms, static_cast<uint8_t>(k)));
      // The camera's counter skips two depth frames after the sixth (lost on the USB).
      Event d = frame(depth_at_ms, 0), c = frame(colour_at_ms, 0);
      d.sequence = c.sequence = k;
      d.pts = static_cast<uint32_t>((colour_capture_ms(k) + 1) * 1000);
      c.pts = static_cast<uint32_t>(colour_capture_ms(k) * 1000);
      d.frame_counter = static_cast<uint32_t>(k + (k >= 6 ? 2 : 0));
      c.frame_counter = static_cast<uint32_t>(k);
      depth_meta.script.push_back(d);
      if (k == kFlaggedColourMetadata) c.kind = Event::kErrorFlag;
      colour_meta.script.push_back(c);
    }
  }
};

TEST(V4l2Nodes, TheMetadataNodesStampAndPairFramesOnTheCamerasClock) {
  const CameraClockScript script;
  D435Rig rig;
  V4l2Source source;
  source.locate_by_usb({0x8086, 0x0b07}, rig.sysfs.c_str(), rig.devfs.c_str());
  source.use_camera_clock(1e6);
  ASSERT_TRUE(source.open(&rig.io, "", "", same_size(kW, kH), 6 * kMs, 500).is_ok());
  ASSERT_TRUE(source.reads_metadata());
  script.play(&rig);
  for (int k = 0; k < CameraClockScript::kFrames; ++k) {
    SensorFrame f;
    Status warning;
    const Status s = source.next(&f, &warning);
    ASSERT_TRUE(s.is_ok()) << k << ": " << s.message();
    EXPECT_EQ(f.depth[0], 100 * k) << "depth and colour of one instant";
    EXPECT_EQ(f.gray[0], k);
    if (k == 0) continue;  // the clock learns the transfer from the first pair
    if (k == CameraClockScript::kFlaggedColourMetadata) {
      // Stamped on arrival: 1 ms apart at capture, 6 ms apart on arrival.
      EXPECT_EQ(f.depth_timestamp_ns - f.timestamp_ns, 6 * kMs);
      continue;
    }
    // The colour transfer's best (3 ms) after capture, for both; 1 ms apart, as captured.
    EXPECT_EQ(f.timestamp_ns, (CameraClockScript::colour_capture_ms(k) + 3) * kMs) << k;
    EXPECT_EQ(f.depth_timestamp_ns - f.timestamp_ns, 1 * kMs) << k;
  }
  const V4l2Counters& c = source.counters();
  EXPECT_EQ(c.unpaired, 0u);
  EXPECT_EQ(c.camera_stamped, static_cast<uint32_t>(CameraClockScript::kFrames - 1));
  EXPECT_EQ(c.metadata_missing, 1u);
  EXPECT_EQ(c.metadata_errors, 1u);
  EXPECT_EQ(c.error_buffers, 0u) << "the frame itself was fine: not counted as an error buffer";
  EXPECT_EQ(c.lost_before_driver, 2u);

  // By arrival alone the same frames drift apart: pairs are broken and frames let go.
  D435Rig by_arrival;
  V4l2Source plain;
  plain.locate_by_usb({0x8086, 0x0b07}, by_arrival.sysfs.c_str(), by_arrival.devfs.c_str());
  ASSERT_TRUE(plain.open(&by_arrival.io, "", "", same_size(kW, kH), 6 * kMs, 500).is_ok());
  EXPECT_FALSE(plain.reads_metadata()) << "no camera clock rate configured";
  script.play(&by_arrival);
  for (;;) {
    SensorFrame f;
    Status warning;
    if (!plain.next(&f, &warning).is_ok()) break;
  }
  EXPECT_GT(plain.counters().unpaired, 0u);
}

TEST(V4l2, ARefusedRequeueIsQueuedAgainAndNoBufferIsLost) {
  Rig rig;
  ASSERT_TRUE(rig.open().is_ok());
  constexpr int kFrames = 10;  // more than the driver's buffers
  for (int i = 0; i < kFrames; ++i) {
    rig.depth->script.push_back(frame(1000 + 33 * i, static_cast<uint8_t>(i)));
    rig.colour->script.push_back(frame(1000 + 33 * i, static_cast<uint8_t>(i)));
  }
  rig.depth->qbuf_failures = 2;  // the first two frames' depth buffers are refused once
  for (int i = 0; i < kFrames; ++i) {
    SensorFrame f;
    Status warning;
    const Status s = rig.source.next(&f, &warning);
    ASSERT_TRUE(s.is_ok()) << i << ": " << s.message();
    EXPECT_EQ(f.timestamp_ns, (1000 + 33 * i) * kMs);
  }
  EXPECT_EQ(rig.source.counters().requeue_failures, 2u);
  EXPECT_EQ(rig.depth->queued.size(), 3u) << "every buffer is back with the driver";
}

TEST(V4l2, TheDepthToColourStampOffsetIsMeasured) {
  Rig rig;
  ASSERT_TRUE(rig.open().is_ok());
  const int offsets_ms[] = {-4, 2, 5, 1};
  for (int i = 0; i < 4; ++i) {
    rig.depth->script.push_back(frame(1000 + 33 * i + offsets_ms[i], 1));
    rig.colour->script.push_back(frame(1000 + 33 * i, 2));
  }
  for (int i = 0; i < 4; ++i) {
    SensorFrame f;
    Status warning;
    ASSERT_TRUE(rig.source.next(&f, &warning).is_ok());
  }
  const V4l2Counters& c = rig.source.counters();
  EXPECT_EQ(c.pair_offset_min_ns, -4 * kMs);
  EXPECT_EQ(c.pair_offset_max_ns, 5 * kMs);
  EXPECT_DOUBLE_EQ(c.mean_pair_offset_ns(), 1.0 * kMs);
}

// Stall recovery on the fake's simulated clock: sleeping moves it forward.
FakeV4l2* g_clock = nullptr;
int64_t fake_now() { return g_clock->now_ns; }
void fake_sleep_until(int64_t t) { g_clock->now_ns = t > g_clock->now_ns ? t : g_clock->now_ns; }

struct RecoveryRig : Rig {
  SensorRecovery recovery;
  std::string sysfs = testing::make_temp_dir("sysfs_v4l2");
  std::string devfs = testing::make_temp_dir("devfs_v4l2");
  RecoveryRig() {
    g_clock = &io;
    RecoveryConfig config;  // 1 s stall, 3 s reopen budget, 100 ms between attempts
    config.reset_usb = true;
    config.usb = {0x2bc5, 0x0401};
    config.sysfs_root = sysfs.c_str();
    config.devfs_root = devfs.c_str();
    EXPECT_TRUE(testing::add_usb_device(sysfs, "1-1", "2bc5", "0401", 1, 7));
    EXPECT_FALSE(testing::add_usbfs_node(devfs, 1, 7).empty());
    recovery.init(&source, config, fake_now, fake_sleep_until);
  }
  // Calls next() until a frame or `calls` errors; the errors' messages in order.
  std::vector<std::string> until_frame(int calls, SensorFrame* f) {
    std::vector<std::string> errors;
    Status warning;
    for (int i = 0; i < calls; ++i) {
      const Status s = recovery.next(f, &warning);
      if (s.is_ok()) break;
      errors.emplace_back(s.message());
    }
    return errors;
  }
};

TEST(V4l2Recovery, AWedgedStreamIsResetAndReopenedAndFramesFlowAgain) {
  RecoveryRig rig;
  ASSERT_TRUE(rig.open().is_ok());
  ASSERT_TRUE(rig.recovery.start(ThreadPlacement()).is_ok());
  rig.depth->script = {frame(1000, 1), frame(3000, 2)};
  rig.colour->script = {frame(1000, 3), frame(3000, 4)};
  SensorFrame f;
  ASSERT_TRUE(rig.until_frame(1, &f).empty());
  rig.depth->wedged = rig.colour->wedged = true;  // the driver stops filling buffers
  const std::vector<std::string> errors = rig.until_frame(10, &f);
  ASSERT_EQ(f.timestamp_ns, 3000 * kMs) << "frames flow again after the reopen";
  // A 500 ms timeout, the stall (one reset-and-reopen, reported as such), and the reopened
  // stream's wait for its first frame.
  ASSERT_EQ(errors.size(), 3u);
  EXPECT_NE(errors[0].find("no frame for 500 ms"), std::string::npos) << errors[0];
  EXPECT_NE(errors[2].find("no frame for 500 ms"), std::string::npos) << errors[2];
  EXPECT_EQ(errors[1].rfind("stall 1000 ms: stream reopened; USB reset failed (", 0), 0u)
      << errors[1];
  EXPECT_NE(errors[1].find(rig.devfs + "/bus/usb/001/007"), std::string::npos) << errors[1];
  const RecoveryCounters& c = rig.recovery.counters();
  EXPECT_EQ(c.stalls, 1u);
  EXPECT_EQ(c.usb_reset_failures, 1u);  // a plain file is no USB device
  EXPECT_EQ(c.reopens, 1u);
  EXPECT_EQ(c.recoveries, 1u);
  EXPECT_EQ(c.last_recovery_ns, 2000 * kMs) << "from the last frame to the first one after";
  EXPECT_EQ(rig.depth->opens, 2);
  EXPECT_EQ(rig.depth->queued.size(), 3u) << "the reopened stream has all its buffers";
}

TEST(V4l2Recovery, AStreamThatRefusesEveryRequeueRunsDryAndIsReopened) {
  RecoveryRig rig;
  ASSERT_TRUE(rig.open().is_ok());
  ASSERT_TRUE(rig.recovery.start(ThreadPlacement()).is_ok());
  for (int i = 0; i < 90; ++i) {  // 3 s of frames
    rig.depth->script.push_back(frame(1000 + 33 * i, 1));
    rig.colour->script.push_back(frame(1000 + 33 * i, 2));
  }
  SensorFrame f;
  ASSERT_TRUE(rig.until_frame(1, &f).empty());
  rig.depth->qbuf_broken = true;  // the driver takes no buffer back until the stream restarts
  int frames = 0;
  for (int i = 0; i < 200 && rig.recovery.counters().recoveries == 0; ++i) {
    Status warning;
    frames += rig.recovery.next(&f, &warning).is_ok() ? 1 : 0;
  }
  const RecoveryCounters& c = rig.recovery.counters();
  EXPECT_EQ(c.stalls, 1u);
  EXPECT_EQ(c.reopens, 1u);
  ASSERT_EQ(c.recoveries, 1u) << "frames flow again after the reopen";
  EXPECT_EQ(frames, 4) << "the three buffers refused in turn, then the frame after the reopen";
  EXPECT_GE(rig.source.counters().requeue_failures, 3u);
  EXPECT_EQ(rig.depth->opens, 2);
}

TEST(V4l2Recovery, AnUnpluggedSensorIsRetriedAtABoundedPaceUntilItIsBack) {
  RecoveryRig rig;
  ASSERT_TRUE(rig.open().is_ok());
  ASSERT_TRUE(rig.recovery.start(ThreadPlacement()).is_ok());
  rig.depth->script = {frame(1000, 1), {Event::kUnplug, 1033 * kMs, 0}};
  rig.colour->script = {frame(1000, 2), frame(1033, 3)};
  SensorFrame f;
  ASSERT_TRUE(rig.until_frame(1, &f).empty());
  // Ten seconds unplugged: the dead device answers at once, yet errors come one frame period
  // apart at most, and a reopen is tried once per stall period, each within its budget.
  int reopen_failures = 0;
  Status warning;
  ASSERT_NE(std::string(rig.recovery.next(&f, &warning).message()).find("unplugged"),
            std::string::npos);
  int64_t previous_ns = rig.io.now_ns;
  while (rig.io.now_ns < 11000 * kMs) {
    const Status s = rig.recovery.next(&f, &warning);
    ASSERT_FALSE(s.is_ok());
    const int64_t step_ns = rig.io.now_ns - previous_ns;
    previous_ns = rig.io.now_ns;
    EXPECT_GE(step_ns, 33 * kMs);
    EXPECT_LE(step_ns, 3100 * kMs) << "one call at most waits out the reopen budget";
    if (std::string(s.message()).find("reopen failed") != std::string::npos) {
      ++reopen_failures;
      EXPECT_NE(std::string(s.message()).find("/dev/video0"), std::string::npos) << s.message();
    }
  }
  EXPECT_GE(reopen_failures, 2);
  EXPECT_LE(reopen_failures, 3) << "one attempt per stall period plus budget";
  EXPECT_EQ(rig.recovery.counters().reopen_failures, static_cast<uint32_t>(reopen_failures));
  // Plugged back in: the next attempt reopens it and frames flow.
  rig.io.unplugged = false;
  const int64_t back_ms = rig.io.now_ns / kMs + 100;
  rig.depth->script = {frame(back_ms, 5)};
  rig.colour->script = {frame(back_ms, 6)};
  const int64_t replugged_ns = rig.io.now_ns;
  ASSERT_LE(rig.until_frame(1000, &f).size(), 60u);
  EXPECT_EQ(f.timestamp_ns, back_ms * kMs);
  EXPECT_LE(rig.io.now_ns - replugged_ns, 1100 * kMs) << "back within one stall period";
  EXPECT_EQ(rig.recovery.counters().reopens, 1u);
  EXPECT_EQ(rig.recovery.counters().recoveries, 1u);
}

TEST(V4l2, TheRealDeviceWhenThereIsOne) {
  SystemV4l2Io io;
  V4l2Source source;
  const Status s =
      source.open(&io, "/dev/video0", "/dev/video1", same_size(640, 480), 20 * kMs, 1000);
  if (!s.is_ok() && std::string(s.message()).find("No such file") != std::string::npos) {
    GTEST_SKIP() << "no /dev/video0 on this machine";
  }
  ASSERT_TRUE(s.is_ok()) << s.message();
  SensorFrame f;
  Status warning;
  EXPECT_TRUE(source.next(&f, &warning).is_ok());
}

}  // namespace
}  // namespace rgbdtam

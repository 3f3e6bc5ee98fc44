// No heap allocation after init: replays the committed clip, runs the firmware, the recorder
// and a V4L2 sensor while counting every allocation (allocation_counting.hpp).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "clip_camera.hpp"
#include "config_files.hpp"
#include "fake_usb.hpp"
#include "fake_v4l2.hpp"
#include "record_job.hpp"
#include "replay_job.hpp"
#include "replay_runner.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/sensor_recovery.hpp"
#include "rgbdtam/hal/udp_link.hpp"
#include "rgbdtam/runtime/registering_sensor.hpp"
#include "run_job.hpp"
#include "stress_variants.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

#include "allocation_counting.hpp"

namespace rgbdtam {
namespace {

TEST(Allocations, CounterSeesAllocations) {
  // Without this, a zero below would prove nothing.
  g_calls = 0;
  g_armed = true;
  g_escape = std::malloc(64);
  std::free(g_escape);
  g_escape = new int(3);
  delete static_cast<int*>(g_escape);
  g_armed = false;
  EXPECT_EQ(g_calls.load(), 2) << "the malloc/new counters are not wired in";
}

TEST(Allocations, InitAllocatesWhatTheMemoryBudgetIsToldItNeeds) {
  // memory_need() refuses configurations the machine cannot hold before init allocates them;
  // it must agree with what init really allocates, for every key that sizes it.
  Params base;
  const std::string config = testing::source_path("config/tum_fr1.conf");
  ASSERT_TRUE(read_params_file(config.c_str(), &base).is_ok());
  Vocabulary vocabulary;
  Status error;
  ASSERT_TRUE(load_vocabulary(base, &vocabulary, &error)) << error.message();
  for (const char* change : {"", "map.keyframe_pool=96", "map.seeds=30000", "map.queue_frames=12",
                             "map.enabled=false", "tracker.photometric_points=20000",
                             "loop.places=4096", "loop.features=1000", "loop.enabled=false"}) {
    Params p = base;
    if (*change != '\0') {
      ASSERT_TRUE(set_param(change, "test", &p).is_ok());
    }
    const Vocabulary* voc = p.loop.enabled ? &vocabulary : nullptr;
    auto system = std::make_unique<SlamSystem>();
    g_bytes = 0;
    g_armed = true;
    ASSERT_TRUE(system->init(p, nullptr, nullptr, voc).is_ok());
    g_armed = false;
    const double allocated = static_cast<double>(g_bytes.load());
    const double needed =
        static_cast<double>(memory_need(p, voc != nullptr ? voc->words() : 0).total());
    std::printf("%-32s init allocated %7.1f MB, memory_need %7.1f MB\n",
                *change != '\0' ? change : "(tum_fr1.conf)", allocated / 1e6, needed / 1e6);
    EXPECT_GE(needed, allocated * 0.98) << change;
    EXPECT_LE(needed, allocated * 1.15) << change;
  }
}

TEST(Allocations, TheSensorThreadAllocatesWhatTheMemoryBudgetCountsForIt) {
  // A D435's depth registered on its own thread: the registration's tables and the frames
  // handed over to the tracker, and no buffer besides (the frames' depth is the buffer).
  Params p;
  const std::string config = testing::source_path("config/realsense_d435.conf");
  ASSERT_TRUE(read_params_file(config.c_str(), &p).is_ok());
  ASSERT_TRUE(p.depth_camera.register_to_colour);
  auto sensor = std::make_unique<RegisteringSensor>();
  g_bytes = 0;
  g_armed = true;
  sensor->init(nullptr, p);
  g_armed = false;
  const double allocated = static_cast<double>(g_bytes.load());
  const double needed = static_cast<double>(RegisteringSensor::bytes_needed(p));
  std::printf("sensor thread: init allocated %.2f MB, bytes_needed %.2f MB\n", allocated / 1e6,
              needed / 1e6);
  EXPECT_GE(needed, allocated * 0.98);
  EXPECT_LE(needed, allocated * 1.05);
}

TEST(Allocations, NoneWhileTrackingTheClipAfterInit) {
  ReplayJob job;
  const long calls = count_allocations_after_init({"map.enabled=false"}, &job);
  EXPECT_EQ(calls, 0) << g_bytes.load() << " bytes allocated after init";
  std::printf(
      "tracking only: %ld allocations after init over 50 frames; PNG arena high water %zu B\n",
      calls, job.source().png_arena_high_water());
}

// Issue 36: registering depth from a camera of its own draws on buffers made at init.
TEST(Allocations, NoneWhileRegisteringDepthFromACameraOfItsOwn) {
  ReplayJob job;
  const long calls = count_allocations_after_init(
      {"map.enabled=false", "depth_camera.fx=560", "depth_camera.fy=560", "depth_camera.cx=322",
       "depth_camera.cy=250", "depth_camera.k1=-0.04", "depth_camera.T_c_d=1 0 0 0 0.025 0 0",
       "depth_camera.register=true"},
      &job);
  EXPECT_EQ(calls, 0) << g_bytes.load() << " bytes allocated after init";
  EXPECT_GT(job.counters().tracked, 40u);
}

TEST(Allocations, NoneWithTheMapperAndLoopModuleSynchronousOrOnTheirOwnThreads) {
  // Every thread's allocations are counted: the loop module's memory is fixed at init too, as
  // it aligns views, adds edges and measures the graph. Over the clip's few keyframes the local
  // window makes every place a neighbour, so views are aligned with it off.
  struct Modes {
    const char* map;
    const char* loop;
    bool window;
  };
  for (const Modes modes : {Modes{"map.threaded=false", "loop.threaded=false", true},
                            Modes{"map.threaded=true", "loop.threaded=true", true},
                            Modes{"map.threaded=true", "loop.threaded=true", false}}) {
    const char* mode = modes.map;
    const char* loop_mode = modes.loop;
    const char* window_mode = modes.window ? "loop.window=true" : "loop.window=false";
    ReplayJob job;
    const long calls =
        count_allocations_after_init({"map.enabled=true", mode, loop_mode, window_mode}, &job);
    EXPECT_GT(job.mapper().counters().keyframes_mapped, 0u) << mode;
    if (modes.window) {
      EXPECT_GT(job.loop().counters().window_edges, 0u) << loop_mode << ": window edges";
    } else {
      EXPECT_GT(job.loop().counters().candidates, 0u) << loop_mode << ": views aligned";
    }
    EXPECT_EQ(calls, 0) << mode << ": " << g_bytes.load() << " bytes allocated after init";
    std::printf(
        "%s, %s, %s: %u keyframes mapped, %u window edges, %u views aligned, %ld "
        "allocations after init\n",
        mode, loop_mode, window_mode, job.mapper().counters().keyframes_mapped,
        job.loop().counters().window_edges, job.loop().counters().candidates, calls);
  }
}

// The local window (loop.window): the second tracking of each new keyframe, its edge and the
// refinements it asks for, blended into the poses sent, in the memory fixed at init. On the
// short clip every disagreement refines (limit 0), so that corrections are sent.
TEST(Allocations, NoneWhileTheLocalWindowRefinesTheMap) {
  ReplayJob job;
  const long calls = count_allocations_after_init(
      {"map.enabled=true", "loop.window=true", "loop.threaded=false",
       "loop.min_window_correction=0", "loop.min_window_correction_angle=0"},
      &job);
  const TrackingCounters c = job.system().tracking().counters();
  std::printf("%u window edges, %u corrections (%u blended), %ld allocations after init\n",
              job.loop().counters().window_edges, c.loop_corrections, c.blended_corrections, calls);
  EXPECT_GT(job.loop().counters().window_edges, 0u);
  EXPECT_GT(c.blended_corrections, 0u);
  EXPECT_EQ(calls, 0) << g_bytes.load() << " bytes allocated after init";
}

TEST(Allocations, NoneWhileRecoveringFromAKidnappedFrame) {
  // Frame 25 of the clip shows what frame 0 showed: its first estimate fails the health checks,
  // so the wider basin and the re-tracking against the last valid frame run, and must allocate
  // nothing either.
  const std::string dir = testing::make_temp_dir("alloc_kidnap");
  ASSERT_TRUE(testing::kidnap_frame(testing::source_path("data/tum_fr1_xyz_clip"),
                                    dir + "/kidnapped", 25, 0));
  ReplayJob job;
  const long calls = count_allocations_after_init({"map.enabled=true"}, &job, dir + "/kidnapped");
  const TrackingCounters& c = job.counters();
  EXPECT_GT(c.retried, 0u) << "the recovery paths must be part of the counted run";
  EXPECT_EQ(calls, 0) << g_bytes.load() << " bytes allocated after init";
  std::printf(
      "kidnapped frame: %u frames, %u retried (%u recovered from guesses, %u against the "
      "last valid frame), %u lost; %ld allocations after init\n",
      c.frames, c.retried, c.recovered_by_guesses, c.recovered_by_last_frame, c.lost, calls);
}

// rgbdtam run on the host-emulation board: paced replay, tracker, mapper thread, link thread
// sending MAVLink over UDP to this test, fake GPIO. Counts from the first frame to the last;
// with count_finish, through finish() too.
long count_firmware_allocations(std::vector<std::string> overrides, RunJob* job,
                                bool count_finish = true, const char* param_override = nullptr) {
  static UdpLink receiver;
  if (receiver.local_port() == 0) {
    EXPECT_TRUE(receiver.open(nullptr, 0, 0).is_ok());
  }
  const std::string board = testing::source_path("board/host-emulation");
  overrides.push_back("link.udp_remote=127.0.0.1:" + std::to_string(receiver.local_port()));
  RunOptions options;
  options.board_dir = board.c_str();
  for (const std::string& o : overrides) {
    options.board_overrides[options.board_override_count++] = o.c_str();
  }
  if (param_override != nullptr) {
    options.param_overrides[options.param_override_count++] = param_override;
  }
  options.progress = false;
  const Status s = job->init(options);
  EXPECT_TRUE(s.is_ok()) << s.message();
  if (!s.is_ok() || !job->start().is_ok()) return -1;  // threads exist: init is complete
  g_calls = 0;
  g_bytes = 0;
  g_armed = true;
  while (job->step()) {
  }
  g_armed = count_finish;
  job->finish();
  g_armed = false;
  return g_calls.load();
}

TEST(Allocations, NoneInTheFirmwareRuntimeAcrossItsThreads) {
  RunJob job;
  const long calls = count_firmware_allocations({}, &job);
  const FirmwareCounters& c = job.runtime().counters();
  EXPECT_EQ(c.frames + job.sensor_dropped(), 50u);
  EXPECT_GT(job.runtime().slam().mapper().counters().keyframes_mapped, 0u);
  EXPECT_EQ(job.runtime().link().counters().odometry_sent, c.frames);
  EXPECT_EQ(calls, 0) << g_bytes.load() << " bytes allocated after init";
  std::printf(
      "firmware runtime: %u frames, %u keyframes mapped, %llu ODOMETRY sent, %ld "
      "allocations after init\n",
      c.frames, job.runtime().slam().mapper().counters().keyframes_mapped,
      static_cast<unsigned long long>(job.runtime().link().counters().odometry_sent), calls);
}

TEST(Allocations, NoneInTheFirmwareRuntimeRegisteringDepthOnTheSensorsThread) {
  const std::string dir = testing::make_temp_dir("alloc_registration_thread");
  const std::string config = testing::clip_in_a_depth_camera_of_its_own(dir);
  ASSERT_FALSE(config.empty());
  RunJob job;
  const long calls =
      count_firmware_allocations({"sensor.device=" + dir + "/d435", "sensor.config=" + config,
                                  "sensor.registration_thread=true"},
                                 &job);
  const FirmwareCounters& c = job.runtime().counters();
  EXPECT_EQ(c.frames + job.sensor_dropped(), 50u);
  EXPECT_GT(c.tracked, 0u);
  EXPECT_EQ(calls, 0) << g_bytes.load() << " bytes allocated after init";
}

TEST(Allocations, NoneInTheFirmwareRuntimeInAMapSavedWhileRunningOrLocalisedIn) {
  // A first run makes the board's map; then, counted, a run that loads and extends it and saves
  // it from the loop thread while running, and a run that localises in it. The save at the end
  // (after the threads have stopped) is not counted.
  const std::string map = "map.file=" + testing::make_temp_dir("alloc_map") + "/board.map";
  {
    RunJob first;
    EXPECT_EQ(count_firmware_allocations({map}, &first, false), 0);
    ASSERT_TRUE(first.map_saved().is_ok()) << first.map_saved().message();
  }
  RunJob slam;
  const long slam_calls = count_firmware_allocations({map, "map.save_period_s=1"}, &slam, false);
  EXPECT_GT(slam.loaded_map().places, 0u);
  EXPECT_GE(slam.map_checkpoint().saves(), 1u) << "a save while running is part of the count";
  EXPECT_EQ(slam_calls, 0) << g_bytes.load() << " bytes allocated after init";
  RunJob localise;
  const long localise_calls =
      count_firmware_allocations({map}, &localise, false, "map.mode=localise");
  EXPECT_GT(localise.runtime().counters().tracked, 0u) << "found in the map";
  EXPECT_EQ(localise_calls, 0) << g_bytes.load() << " bytes allocated after init";
  std::printf(
      "map loaded (%u places): slam with %u saves while running, %ld allocations; "
      "localise, %u frames tracked, %ld allocations\n",
      slam.loaded_map().places, slam.map_checkpoint().saves(), slam_calls,
      localise.runtime().counters().tracked, localise_calls);
}

TEST(Allocations, NoneWhileRecordingAfterInit) {
  const std::string out = testing::make_temp_dir("alloc_record") + "/recording";
  const std::string board = testing::source_path("board/host-emulation");
  RunOptions options;
  options.board_dir = board.c_str();
  options.progress = false;
  RecordJob job;
  ASSERT_TRUE(job.init(options, out.c_str()).is_ok());
  ASSERT_TRUE(job.start().is_ok());
  g_calls = 0;
  g_bytes = 0;
  g_armed = true;
  while (job.step()) {
  }
  const Status s = job.finish();
  g_armed = false;
  ASSERT_TRUE(s.is_ok()) << s.message();
  EXPECT_GT(job.recorder().counters().written, 0u);
  EXPECT_EQ(g_calls.load(), 0) << g_bytes.load() << " bytes allocated after init";
  std::printf("recorder: %u frames written, %ld allocations after init\n",
              job.recorder().counters().written, g_calls.load());
}

}  // namespace
}  // namespace rgbdtam

namespace rgbdtam {
namespace {
testing::FakeV4l2* g_v4l2 = nullptr;
int64_t v4l2_now() { return g_v4l2->now_ns; }
void v4l2_sleep_until(int64_t t) { g_v4l2->now_ns = t > g_v4l2->now_ns ? t : g_v4l2->now_ns; }

TEST(Allocations, NoneWhileAV4l2SensorDeliversSkipsAndTimesOut) {
  // The V4L2 backend behind the stall recovery, on the scripted fake: paired frames, a buffer
  // flagged as an error, EINTR, refused requeues, a tracker that fell behind, and a short
  // silence (timeouts).
  testing::FakeV4l2 io;
  g_v4l2 = &io;
  io.nodes.reserve(2);
  testing::FakeV4l2::Node& depth = io.add("/dev/video0", V4L2_PIX_FMT_Z16);
  testing::FakeV4l2::Node& colour = io.add("/dev/video1", V4L2_PIX_FMT_YUYV);
  for (int i = 0; i < 60; ++i) {
    const int64_t t_ms = 1000 + 33 * i + (i >= 40 ? 1200 : 0);  // silent for 1.2 s at frame 40
    depth.script.push_back(testing::frame(t_ms, static_cast<uint8_t>(i)));
    colour.script.push_back(testing::frame(t_ms + 1, static_cast<uint8_t>(i)));
    if (i == 10) depth.script.push_back({testing::Event::kErrorFlag, (t_ms + 5) * 1'000'000, 0});
    if (i == 20) colour.script.push_back({testing::Event::kEintr, (t_ms + 5) * 1'000'000, 0});
  }
  io.now_ns = 900 * testing::kMs;
  V4l2Source source;
  ASSERT_TRUE(source
                  .open(&io, "/dev/video0", "/dev/video1", same_size(testing::kW, testing::kH),
                        10 * testing::kMs, 500)
                  .is_ok());
  SensorRecovery recovery;
  RecoveryConfig config;
  config.stall_ns = 5'000'000'000;  // a reopen maps buffers anew: not part of streaming
  recovery.init(&source, config, v4l2_now, v4l2_sleep_until);
  ASSERT_TRUE(recovery.start(ThreadPlacement()).is_ok());
  int frames = 0, errors = 0;
  g_calls = 0;
  g_bytes = 0;
  g_armed = true;
  for (int call = 0; call < 80 && (!depth.script.empty() || !colour.script.empty()); ++call) {
    if (call == 30) io.now_ns += 100 * testing::kMs;  // the tracker fell behind
    if (call == 25) depth.qbuf_failures = 2;
    SensorFrame f;
    Status warning;
    recovery.next(&f, &warning).is_ok() ? ++frames : ++errors;
  }
  g_armed = false;
  EXPECT_GT(frames, 50);
  EXPECT_GE(errors, 2) << "the silence must be part of the counted run";
  EXPECT_GT(source.counters().error_buffers + source.counters().retries, 1u);
  EXPECT_GT(source.dropped(), 0u);
  EXPECT_EQ(source.counters().requeue_failures, 2u);
  EXPECT_EQ(g_calls.load(), 0) << g_bytes.load() << " bytes allocated while streaming";
  std::printf("v4l2 + recovery: %d frames, %d errors, %u dropped, %ld allocations\n", frames,
              errors, source.dropped(), g_calls.load());
}

// A D435 found by its USB id, its metadata nodes read beside its video nodes: every frame's
// metadata is found, parsed and put on the camera's clock without the heap.
TEST(Allocations, NoneWhileReadingTheCamerasClockFromItsMetadataNodes) {
  const std::string sysfs = testing::make_temp_dir("alloc_sysfs");
  const std::string devfs = testing::make_temp_dir("alloc_devfs");
  ASSERT_TRUE(testing::add_usb_device(sysfs, "2-1", "8086", "0b07", 2, 3));
  testing::FakeV4l2 io;
  io.nodes.reserve(4);
  const char* interface_of[] = {"2-1:1.0", "2-1:1.0", "2-1:1.3", "2-1:1.3"};
  const uint32_t fourcc_of[] = {V4L2_PIX_FMT_Z16, 0, V4L2_PIX_FMT_YUYV, 0};
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(testing::add_video_node(sysfs, "2-1", interface_of[i], 2 + i));
    testing::FakeV4l2::Node& n = io.add(devfs + "/video" + std::to_string(2 + i), fourcc_of[i]);
    n.metadata = fourcc_of[i] == 0;
    n.meta_format = V4L2_META_FMT_D4XX;
  }
  for (int i = 0; i < 40; ++i) {
    const int64_t t_ms = 1000 + 33 * i;
    for (int n = 0; n < 4; ++n) {
      testing::Event e = testing::frame(t_ms + n / 2 + i % 3, static_cast<uint8_t>(i));
      e.sequence = i;
      e.pts = static_cast<uint32_t>((t_ms - 5) * 1000);
      e.frame_counter = static_cast<uint32_t>(i + (i > 20 ? 1 : 0));
      io.nodes[n].script.push_back(e);
    }
  }
  io.now_ns = 900 * testing::kMs;
  V4l2Source source;
  source.locate_by_usb({0x8086, 0x0b07}, sysfs.c_str(), devfs.c_str());
  source.use_camera_clock(1e6);
  ASSERT_TRUE(source.open(&io, "", "", same_size(testing::kW, testing::kH), 10 * testing::kMs, 500)
                  .is_ok());
  ASSERT_TRUE(source.reads_metadata());
  g_calls = 0;
  g_bytes = 0;
  g_armed = true;
  int frames = 0;
  for (int i = 0; i < 40; ++i) {
    SensorFrame f;
    Status warning;
    frames += source.next(&f, &warning).is_ok();
  }
  g_armed = false;
  EXPECT_EQ(frames, 40);
  EXPECT_EQ(source.counters().camera_stamped, 40u);
  EXPECT_EQ(source.counters().lost_before_driver, 2u) << "depth's and colour's counters skip one";
  EXPECT_EQ(g_calls.load(), 0) << g_bytes.load() << " bytes allocated while streaming";
}

// A UVC camera sending MJPEG at full resolution: libjpeg decodes every frame from the arena
// JpegDecoder sized at open, never from the heap.
TEST(Allocations, NoneWhileDecodingMjpegColourFrames) {
  std::vector<std::vector<uint8_t>> gray;
  std::vector<std::vector<uint16_t>> depth;
  ASSERT_TRUE(
      testing::ClipCamera::load(testing::source_path("data/tum_fr1_xyz_clip"), &gray, &depth));
  std::vector<std::vector<uint8_t>> jpeg;
  for (const auto& g : gray) jpeg.push_back(testing::encode_jpeg(g.data(), 640, 480, 90));
  testing::ClipCamera camera(gray, depth, 640, 480, 30.0, {});
  camera.send_mjpeg(jpeg);
  V4l2Source source;
  ASSERT_TRUE(source
                  .open(&camera, "/dev/soak-depth", "/dev/soak-colour", same_size(640, 480),
                        20'000'000, 1000, V4l2Colour::kMjpeg)
                  .is_ok());
  SensorFrame f;
  Status warning;
  ASSERT_TRUE(source.next(&f, &warning).is_ok());  // the first frame: libjpeg's tables
  g_calls = 0;
  g_bytes = 0;
  g_armed = true;
  int frames = 0;
  for (int i = 0; i < 20; ++i) frames += source.next(&f, &warning).is_ok();
  g_armed = false;
  EXPECT_EQ(frames, 20);
  EXPECT_EQ(source.jpeg().decoded(), 21u);
  EXPECT_EQ(g_calls.load(), 0) << g_bytes.load() << " bytes allocated while decoding";
  std::printf("MJPEG: %u frames decoded, %ld allocations; libjpeg's arena peak %zu kB of %zu kB\n",
              source.jpeg().decoded(), g_calls.load(), source.jpeg().arena().peak_bytes() / 1024,
              source.jpeg().arena().capacity_bytes() / 1024);
}
}  // namespace
}  // namespace rgbdtam

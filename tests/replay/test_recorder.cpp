// The recorder: PNG encoding round trips exactly, and `rgbdtam record` of a replayed sensor
// gives a TUM folder whose frames, values and timestamps equal the source's.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <csignal>
#include <fstream>

#include <random>
#include <string>
#include <vector>

#include "record_job.hpp"
#include "rgbdtam/hal/png_decoder.hpp"
#include "rgbdtam/hal/png_encoder.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

TEST(PngEncoder, GreyAndDepthRoundTripExactlyEvenWhenIncompressible) {
  constexpr int w = 640, h = 480;
  std::mt19937 rng(7);
  std::vector<uint8_t> gray(w * h);
  std::vector<uint16_t> depth(w * h);
  for (auto& g : gray) g = static_cast<uint8_t>(rng());
  for (auto& d : depth) d = static_cast<uint16_t>(rng());
  PngEncoder enc;
  enc.allocate(w, h);
  PngDecoder dec;
  dec.allocate(w);
  ASSERT_TRUE(enc.encode_gray8(gray.data(), w, h).is_ok());
  std::vector<uint8_t> gray_back(w * h);
  ASSERT_TRUE(dec.decode_gray8(enc.data(), enc.size(), w, h, gray_back.data()).is_ok());
  EXPECT_EQ(gray_back, gray);
  ASSERT_TRUE(enc.encode_gray16(depth.data(), w, h).is_ok());
  std::vector<uint16_t> depth_back(w * h);
  ASSERT_TRUE(dec.decode_gray16(enc.data(), enc.size(), w, h, depth_back.data()).is_ok());
  EXPECT_EQ(depth_back, depth);
}

struct Frame {
  int64_t t_ns, depth_t_ns;
  std::vector<uint8_t> gray;
  std::vector<uint16_t> depth;
};

std::vector<Frame> read_all(const std::string& folder) {
  TumReplaySource src;
  EXPECT_TRUE(src.open(folder.c_str(), same_size(640, 480), 20'000'000, 20'000'000).is_ok())
      << folder;
  std::vector<Frame> out;
  SensorFrame f;
  Status warning;
  while (src.next(&f, &warning).is_ok()) {
    Frame c{
        f.timestamp_ns, f.depth_timestamp_ns, std::vector<uint8_t>(f.gray, f.gray + 640 * 480), {}};
    if (f.depth != nullptr) c.depth.assign(f.depth, f.depth + 640 * 480);
    out.push_back(std::move(c));
  }
  return out;
}

// `rgbdtam record --board board/host-emulation <out>`: the committed clip at its own rate.
Status init_recording(RecordJob* job, const std::string& out) {
  static const std::string board = testing::source_path("board/host-emulation");
  RunOptions options;
  options.board_dir = board.c_str();
  options.progress = false;
  return job->init(options, out.c_str());
}

TEST(Recorder, RecordingAReplayedSensorGivesTheSameFrames) {
  const std::string out = testing::make_temp_dir("recorder") + "/recording";
  RecordJob job;
  ASSERT_TRUE(init_recording(&job, out).is_ok());
  ASSERT_TRUE(job.start().is_ok());
  while (job.step()) {
  }
  ASSERT_TRUE(job.finish().is_ok());
  const RecorderCounters c = job.recorder().counters();
  EXPECT_EQ(c.written + c.dropped + job.sensor_dropped(), 50u);
  std::printf("recorded %u frames, %u dropped at the recorder, %u by the sensor; %.2f ms/frame\n",
              c.written, c.dropped, job.sensor_dropped(),
              job.recorder().time_per_frame().percentile_ms(0.5));

  const std::vector<Frame> source = read_all(testing::source_path("data/tum_fr1_xyz_clip"));
  const std::vector<Frame> recorded = read_all(out);
  ASSERT_EQ(recorded.size(), c.written);
  size_t s = 0;
  for (const Frame& r : recorded) {
    while (s < source.size() && source[s].t_ns != r.t_ns) ++s;  // frames dropped under load
    ASSERT_LT(s, source.size()) << "recorded a frame the source does not have";
    EXPECT_EQ(r.depth_t_ns, source[s].depth_t_ns);
    EXPECT_TRUE(r.gray == source[s].gray) << "frame at " << r.t_ns;
    EXPECT_TRUE(r.depth == source[s].depth) << "frame at " << r.t_ns;
  }
}

TEST(Recorder, ADepthCameraOfItsOwnSizeIsRecordedAtItAndReadBackOnlyAtIt) {
  // A D435 over V4L2 delivers depth as its depth camera sees it (848x480 beside 640x480): here
  // 80x40 beside 64x48.
  const SensorImageSize size{64, 48, 80, 40};
  const std::string out = testing::make_temp_dir("recorder_sizes") + "/recording";
  std::vector<uint8_t> gray(size.pixels());
  std::vector<uint16_t> depth(size.depth_pixels());
  for (size_t i = 0; i < gray.size(); ++i) gray[i] = static_cast<uint8_t>(i);
  for (size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<uint16_t>(1000 + i);
  TumRecorder recorder;
  ASSERT_TRUE(recorder.open(out.c_str(), size).is_ok());
  ASSERT_TRUE(recorder.start(ThreadPlacement{}).is_ok());
  SensorFrame f;
  f.timestamp_ns = 1'000'000'000;
  f.depth_timestamp_ns = 1'005'000'000;
  f.gray = gray.data();
  f.depth = depth.data();
  f.width_px = size.width_px;
  f.height_px = size.height_px;
  f.depth_width_px = size.depth_width_px;
  f.depth_height_px = size.depth_height_px;
  EXPECT_TRUE(recorder.push(f));
  SensorFrame registered = f;  // depth at colour's size: not what the recording was opened for
  registered.timestamp_ns += 33'000'000;
  registered.depth_width_px = size.width_px;
  registered.depth_height_px = size.height_px;
  EXPECT_FALSE(recorder.push(registered));
  ASSERT_TRUE(recorder.finish().is_ok());
  EXPECT_EQ(recorder.counters().written, 1u);
  EXPECT_EQ(recorder.counters().dropped, 1u);

  TumReplaySource replay;
  ASSERT_TRUE(replay.open(out.c_str(), size, 20'000'000, 0).is_ok());
  SensorFrame back;
  Status warning;
  ASSERT_TRUE(replay.next(&back, &warning).is_ok());
  ASSERT_NE(back.depth, nullptr) << warning.message();
  EXPECT_EQ(back.depth_width_px, size.depth_width_px);
  EXPECT_EQ(back.depth_height_px, size.depth_height_px);
  EXPECT_TRUE(std::equal(depth.begin(), depth.end(), back.depth));
  EXPECT_TRUE(std::equal(gray.begin(), gray.end(), back.gray));
  // Replayed with a config that forgot the depth camera's size: the frame comes without depth,
  // and the warning says why.
  TumReplaySource forgot;
  ASSERT_TRUE(forgot.open(out.c_str(), same_size(64, 48), 20'000'000, 0).is_ok());
  ASSERT_TRUE(forgot.next(&back, &warning).is_ok());
  EXPECT_EQ(back.depth, nullptr);
  EXPECT_NE(std::string(warning.message()).find("PNG is 80x40, expected 64x48"), std::string::npos)
      << warning.message();
}

TEST(Recorder, RefusesToOverwriteARecordingAndNamesBadFolders) {
  const std::string out = testing::make_temp_dir("recorder_twice");
  TumRecorder first;
  ASSERT_TRUE(first.open(out.c_str(), same_size(64, 48)).is_ok());
  ASSERT_TRUE(first.finish().is_ok());
  TumRecorder second;
  const Status again = second.open(out.c_str(), same_size(64, 48));
  ASSERT_FALSE(again.is_ok());
  EXPECT_NE(std::string(again.message()).find("holds a recording already"), std::string::npos);
  TumRecorder bad;
  const Status s = bad.open("/proc/rgbdtam-cannot-write-here", same_size(64, 48));
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("/proc/rgbdtam-cannot-write-here"), std::string::npos);
}

TEST(Recorder, AWriteFailureStopsTheRecordingAndNothingUnwrittenIsListed) {
  // A file-size limit fails writes like a full disk does, for this process only.
  const std::string out = testing::make_temp_dir("recorder_full") + "/recording";
  RecordJob job;
  ASSERT_TRUE(init_recording(&job, out).is_ok());
  rlimit old_limit;
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);  // EFBIG instead of a signal
  rlimit small = old_limit;
  small.rlim_cur = 150 * 1024;  // a grey PNG of the clip is about 200 KB
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  ASSERT_TRUE(job.start().is_ok());
  int steps = 0;
  while (job.step()) ++steps;
  const Status s = job.finish();
  ::setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find(out + "/rgb/"), std::string::npos) << s.message();
  EXPECT_NE(std::string(s.message()).find("File too large"), std::string::npos) << s.message();
  EXPECT_LT(steps, 45) << "the recording stopped soon after the failure";
  // Every listed image is on disk, whole.
  for (const char* list : {"/rgb.txt", "/depth.txt"}) {
    std::ifstream in(out + list);
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      const std::string file = out + "/" + line.substr(line.find(' ') + 1);
      struct stat st;
      EXPECT_TRUE(::stat(file.c_str(), &st) == 0 && st.st_size > 0) << file;
    }
  }
  std::printf("stopped after %d frames: %s\n", steps, s.message());
}

}  // namespace
}  // namespace rgbdtam

// Replay input: TUM lists, timestamps, PNG decoding, and bad input of every kind reported
// and skipped, never a crash.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "replay_job.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/ply_map_writer.hpp"
#include "rgbdtam/hal/replay_sensor.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"
#include "rgbdtam/hal/tum_timestamp.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

TEST(Timestamps, ExactNanosecondsBothWays) {
  int64_t ns = 0;
  ASSERT_NE(parse_seconds_ns("1305031102.175304 rgb/x.png", &ns), nullptr);
  EXPECT_EQ(ns, 1305031102175304000LL);
  char buf[32];
  format_seconds(ns, buf, sizeof(buf));
  EXPECT_STREQ(buf, "1305031102.175304");
  ASSERT_NE(parse_seconds_ns("12.000000001", &ns), nullptr);
  format_seconds(ns, buf, sizeof(buf));
  EXPECT_STREQ(buf, "12.000000001");
  EXPECT_EQ(parse_seconds_ns("rgb/x.png", &ns), nullptr);
  EXPECT_EQ(parse_seconds_ns("", &ns), nullptr);
  ASSERT_NE(parse_seconds_ns("9999999999.5", &ns), nullptr);
  EXPECT_EQ(ns, INT64_MAX) << "beyond int64 nanoseconds: saturated, never wrapped";
  ASSERT_NE(parse_seconds_ns("-99999999999999999999999", &ns), nullptr);
  EXPECT_EQ(ns, -INT64_MAX);
}

TEST(TumList, SkipsCommentsAndCountsBadLines) {
  TumList list;
  const char* text =
      "# color images\n2.0 rgb/b.png\n1.0 rgb/a.png\n\n3.0\nnot-a-stamp rgb/c.png\n4.0 rgb/d.png";
  ASSERT_TRUE(parse_tum_list(text, "rgb.txt", &list).is_ok());
  ASSERT_EQ(list.size, 3);
  EXPECT_EQ(list.bad_lines, 2);
  EXPECT_STREQ(list.entries[0].path, "rgb/a.png");  // sorted by time
  EXPECT_STREQ(list.entries[2].path, "rgb/d.png");  // no newline at the end is fine
  EXPECT_NE(std::string(list.first_problem.message()).find("rgb.txt:5"), std::string::npos)
      << list.first_problem.message();
  EXPECT_FALSE(parse_tum_list("# only comments\n", "empty.txt", &list).is_ok());
  // Stamps out of any recording's range are errors for their line, not overflows for others.
  ASSERT_TRUE(parse_tum_list("1.0 a.png\n9999999999.5 b.png\n-3.0 c.png\n4100000000 d.png\n",
                             "rgb.txt", &list)
                  .is_ok());
  EXPECT_EQ(list.size, 1);
  EXPECT_EQ(list.bad_lines, 3);
  EXPECT_NE(std::string(list.first_problem.message()).find("rgb.txt:2: timestamp out of range"),
            std::string::npos)
      << list.first_problem.message();
  // Old Mac line endings read every line; a stamp listed twice keeps its first image.
  ASSERT_TRUE(
      parse_tum_list("1.0 a.png\r2.0 b.png\r2.0 c.png\r3.0 d.png", "rgb.txt", &list).is_ok());
  EXPECT_EQ(list.size, 3);
  EXPECT_EQ(list.bad_lines, 1);
  EXPECT_STREQ(list.entries[1].path, "b.png");
  EXPECT_NE(std::string(list.first_problem.message()).find("2.000000 listed again (c.png)"),
            std::string::npos)
      << list.first_problem.message();
  // Memory follows the entries, not the lines; a list too long for any recording is refused.
  EXPECT_FALSE(parse_tum_list(std::string(4'000'000, '\n').c_str(), "blank.txt", &list).is_ok());
  std::string huge;
  for (int i = 0; i <= 1'000'000; ++i) huge += "1 a\n";
  const Status s = parse_tum_list(huge.c_str(), "huge.txt", &list);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("1000001 entries, more than"), std::string::npos)
      << s.message();
}

TEST(PngDecoder, ColourBecomesBt601GreyAndBadFilesAreErrors) {
  const std::string dir = testing::make_temp_dir("png");
  std::vector<uint8_t> rgb(16 * 8 * 3);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>(i * 37 % 256);
  ASSERT_TRUE(testing::write_png_rgb8(dir + "/c.png", 16, 8, rgb.data()));
  std::vector<uint8_t> file(1 << 16);
  size_t size = 0;
  ASSERT_TRUE(read_file((dir + "/c.png").c_str(), file.data(), file.size(), &size).is_ok());
  PngDecoder png;
  png.allocate(16);
  std::vector<uint8_t> gray(16 * 8);
  ASSERT_TRUE(png.decode_gray8(file.data(), size, 16, 8, gray.data()).is_ok());
  for (int i = 0; i < 16 * 8; ++i) {
    const int expect =
        (299 * rgb[3 * i] + 587 * rgb[3 * i + 1] + 114 * rgb[3 * i + 2] + 500) / 1000;
    EXPECT_EQ(gray[static_cast<size_t>(i)], expect);
  }
  EXPECT_FALSE(png.decode_gray8(file.data(), size, 17, 8, gray.data()).is_ok()) << "wrong size";
  EXPECT_FALSE(png.decode_gray8(file.data(), size / 2, 16, 8, gray.data()).is_ok()) << "truncated";
  std::vector<uint8_t> flipped(file.begin(), file.begin() + static_cast<long>(size));
  flipped[size / 2] ^= 0xFF;
  EXPECT_FALSE(png.decode_gray8(flipped.data(), size, 16, 8, gray.data()).is_ok()) << "bad CRC";
  std::vector<uint16_t> depth(16 * 8);
  EXPECT_FALSE(png.decode_gray16(file.data(), size, 16, 8, depth.data()).is_ok())
      << "a colour PNG is not depth";
  const uint8_t garbage[64] = {1, 2, 3};
  EXPECT_FALSE(png.decode_gray8(garbage, sizeof(garbage), 16, 8, gray.data()).is_ok());
}

class BrokenSequence : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::make_temp_dir("seq");
    ASSERT_TRUE(testing::write_synthetic_sequence(dir_, scene_, kFrames, 10.0));
    std::ifstream in(dir_ + "/rgb.txt");
    std::ifstream din(dir_ + "/depth.txt");
    std::string line;
    while (std::getline(in, line))
      if (line[0] != '#') rgb_.push_back(line.substr(line.find(' ') + 1));
    while (std::getline(din, line))
      if (line[0] != '#') depth_.push_back(line.substr(line.find(' ') + 1));
  }
  std::vector<std::string> deliver_all(int* skipped, int* without_depth) {
    TumReplaySource src;
    EXPECT_TRUE(src.open(dir_.c_str(), same_size(kWidth, kHeight), 20'000'000, 0).is_ok());
    std::vector<std::string> problems;
    *skipped = *without_depth = 0;
    for (;;) {
      SensorFrame f;
      Status warning;
      const Status s = src.next(&f, &warning);
      if (s.code() == StatusCode::kEndOfStream) break;
      if (!s.is_ok()) {
        ++*skipped;
        problems.push_back(s.message());
        continue;
      }
      if (f.depth == nullptr) {
        ++*without_depth;
        problems.push_back(warning.message());
      }
    }
    return problems;
  }
  static constexpr int kFrames = 8;
  static constexpr int kWidth = 320, kHeight = 240;
  testing::SyntheticScene scene_ = testing::SyntheticScene::half_resolution();
  std::string dir_;
  std::vector<std::string> rgb_, depth_;
};

TEST_F(BrokenSequence, CleanSequenceDeliversEveryFrameWithDepth) {
  int skipped, without_depth;
  deliver_all(&skipped, &without_depth);
  EXPECT_EQ(skipped, 0);
  EXPECT_EQ(without_depth, 0);
}

TEST_F(BrokenSequence, CorruptAndMissingImagesAreReportedAndSkipped) {
  // Frame 2's colour image is garbage, frame 4's is truncated, frame 6's depth is missing.
  ASSERT_TRUE(testing::write_text(dir_ + "/" + rgb_[2], "this is not a PNG file at all"));
  {
    std::ifstream in(dir_ + "/" + rgb_[4], std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream out(dir_ + "/" + rgb_[4], std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size() / 3));
  }
  ASSERT_EQ(::unlink((dir_ + "/" + depth_[6]).c_str()), 0);
  int skipped, without_depth;
  const auto problems = deliver_all(&skipped, &without_depth);
  EXPECT_EQ(skipped, 2);
  EXPECT_EQ(without_depth, 1);
  ASSERT_EQ(problems.size(), 3u);
  EXPECT_NE(problems[0].find(rgb_[2]), std::string::npos) << problems[0];
  EXPECT_NE(problems[1].find("truncated"), std::string::npos) << problems[1];
  EXPECT_NE(problems[2].find(depth_[6]), std::string::npos) << problems[2];
}

TEST_F(BrokenSequence, TruncatedListFileKeepsTheGoodLines) {
  // Cut rgb.txt in the middle of its last line, as an interrupted copy would.
  std::ifstream in(dir_ + "/rgb.txt");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.resize(text.size() - rgb_.back().size() - 1);
  ASSERT_TRUE(testing::write_text(dir_ + "/rgb.txt", text));
  TumReplaySource src;
  ASSERT_TRUE(src.open(dir_.c_str(), same_size(kWidth, kHeight), 20'000'000, 0).is_ok());
  EXPECT_EQ(src.frame_count(), kFrames - 1);
  EXPECT_EQ(src.rgb_list().bad_lines, 1);
}

TEST_F(BrokenSequence, MissingDepthFrameInTheListMeansNoDepthForThatFrame) {
  // Drop depth line 3 from depth.txt: colour frame 3 has no depth within 20 ms any more.
  std::string text = "# depth\n";
  for (size_t i = 0; i < depth_.size(); ++i) {
    if (i == 3) continue;
    text += depth_[i].substr(6, depth_[i].size() - 10) + " " + depth_[i] + "\n";
  }
  ASSERT_TRUE(testing::write_text(dir_ + "/depth.txt", text));
  int skipped, without_depth;
  const auto problems = deliver_all(&skipped, &without_depth);
  EXPECT_EQ(skipped, 0);
  EXPECT_EQ(without_depth, 1);
  ASSERT_FALSE(problems.empty());
  EXPECT_NE(problems[0].find("no depth frame"), std::string::npos) << problems[0];
}

TEST_F(BrokenSequence, ReplayTracksThroughBrokenFrames) {
  ASSERT_TRUE(testing::write_text(dir_ + "/" + rgb_[3], "garbage"));
  ASSERT_EQ(::unlink((dir_ + "/" + depth_[5]).c_str()), 0);
  ASSERT_TRUE(testing::write_text(dir_ + "/synthetic.conf", testing::synthetic_config(scene_)));
  ReplayOptions opt;
  opt.sequence = dir_.c_str();
  opt.progress = false;
  char* text = nullptr;
  ASSERT_TRUE(read_text_file((dir_ + "/synthetic.conf").c_str(), 4096, &text).is_ok());
  ASSERT_TRUE(parse_params(text, "synthetic.conf", &opt.params).is_ok());
  delete[] text;
  ReplayJob job;
  ASSERT_TRUE(job.init(opt).is_ok());
  while (job.step()) {
  }
  ASSERT_TRUE(job.finish().is_ok());
  EXPECT_EQ(job.source().counters().skipped, 1u);
  EXPECT_EQ(job.counters().without_depth, 1u);
  EXPECT_EQ(job.counters().tracked, static_cast<uint32_t>(kFrames - 1));
}

// A test's run must not depend on how busy the machine is: held, a replay at 1000 Hz to a
// tracker that takes 20 ms a frame still hands over every frame, in order.
TEST(ReplaySensor, HeldEveryFrameReachesASlowTrackerInOrder) {
  const testing::SyntheticScene scene = testing::SyntheticScene::half_resolution();
  const std::string dir = testing::make_temp_dir("held");
  constexpr int kFrames = 8;
  ASSERT_TRUE(testing::write_synthetic_sequence(dir, scene, kFrames, 1000.0));
  TumReplaySource source;
  ASSERT_TRUE(source
                  .open(dir.c_str(), same_size(scene.camera.width_px, scene.camera.height_px),
                        20'000'000, 0)
                  .is_ok());
  ReplaySensor sensor;
  sensor.open(&source);
  sensor.hold_every_frame();
  ASSERT_TRUE(sensor.start(ThreadPlacement{}).is_ok());
  std::vector<int64_t> stamps;
  for (;;) {
    SensorFrame frame;
    Status warning;
    const Status s = sensor.next(&frame, &warning);
    if (s.code() == StatusCode::kEndOfStream) break;
    ASSERT_TRUE(s.is_ok()) << s.message();
    stamps.push_back(frame.timestamp_ns);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // a slow tracker
  }
  sensor.stop();
  ASSERT_EQ(static_cast<int>(stamps.size()), kFrames);
  for (int i = 1; i < kFrames; ++i) EXPECT_GT(stamps[i], stamps[i - 1]);
  EXPECT_EQ(sensor.dropped(), 0u);
}

TEST(ReplaySource, MissingFolderIsAClearError) {
  TumReplaySource src;
  const Status s = src.open("/nonexistent/sequence", same_size(640, 480), 20'000'000, 0);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("/nonexistent/sequence/rgb.txt"), std::string::npos);
}

TEST(ReplaySource, AFifoInPlaceOfAFileIsRefusedNotWaitedOn) {
  // Opening a FIFO for reading blocks until a writer comes: replay used to hang there.
  const std::string dir = testing::make_temp_dir("fifo");
  ASSERT_EQ(::mkfifo((dir + "/rgb.txt").c_str(), 0644), 0);
  TumReplaySource src;
  const Status s = src.open(dir.c_str(), same_size(640, 480), 20'000'000, 0);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("rgb.txt: not a regular file"), std::string::npos)
      << s.message();
  char* text = nullptr;
  EXPECT_FALSE(read_text_file("/dev/zero", 1 << 20, &text).is_ok());
}

}  // namespace
}  // namespace rgbdtam

namespace rgbdtam {
namespace {

TEST(PlyMapWriter, WritesBinaryVerticesAndPatchesTheCount) {
  const std::string path = testing::make_temp_dir("ply") + "/map.ply";
  FixedVector<FusedPixel> pixels;
  pixels.reserve_once(4);
  ASSERT_TRUE(pixels.push_back({100, 50, 0.5f, 0.01f, 1.0f, DepthSource::kSensor}));
  ASSERT_TRUE(pixels.push_back({320, 240, 0.25f, 0.01f, 0.5f, DepthSource::kMultiView}));
  const PinholeIntrinsics k{500, 500, 320, 240, 640, 480};
  PlyMapWriter ply;
  ASSERT_TRUE(ply.open(path.c_str()).is_ok());
  ply.on_keyframe_map(0, SE3(), k, pixels);
  ply.on_keyframe_map(1, SE3(Eigen::Quaterniond::Identity(), Vector3d(1, 0, 0)), k, pixels);
  ASSERT_TRUE(ply.close().is_ok());
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(bytes.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(bytes.find("element vertex 0000000004\n"), std::string::npos);
  const size_t body = bytes.find("end_header\n") + std::strlen("end_header\n");
  ASSERT_EQ(bytes.size() - body, 4u * 15u);
  // Vertex 1: pixel (320, 240) at 4 m is (0, 0, 4), grey 128 (0.5, rounded).
  float xyz[3];
  std::memcpy(xyz, bytes.data() + body + 15, sizeof(xyz));
  EXPECT_FLOAT_EQ(xyz[0], 0.f);
  EXPECT_FLOAT_EQ(xyz[2], 4.f);
  EXPECT_EQ(static_cast<uint8_t>(bytes[body + 15 + 12]), 128);
  // Vertex 3 is the same pixel seen from a keyframe 1 m to the right.
  std::memcpy(xyz, bytes.data() + body + 3 * 15, sizeof(xyz));
  EXPECT_FLOAT_EQ(xyz[0], 1.f);
}

}  // namespace
}  // namespace rgbdtam

// The map file on the committed clip: a second session localises in the first one's map and
// reports poses in its world frame; localise mode leaves the map as it was; damaged and
// mismatched files are refused with the reason; a writer killed at any instant leaves a map that
// loads.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>

#include "config_files.hpp"
#include "map_files.hpp"
#include "replay_runner.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "stress_variants.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

const std::string kClip = testing::source_path("data/tum_fr1_xyz_clip");
const std::string kConfig = testing::source_path("config/tum_fr1.conf");

std::vector<uint8_t> bytes_of(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), {});
}

void write_bytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// Both sessions' poses under one alignment to the ground truth: proof that they share a frame.
EvaluationReport evaluate_together(const testing::ReplayOutcome& a,
                                   const testing::ReplayOutcome& b) {
  std::vector<StampedPose> gt;
  int bad = 0;
  EXPECT_TRUE(read_tum_trajectory((kClip + "/groundtruth.txt").c_str(), &gt, &bad).is_ok());
  std::vector<StampedPose> both = a.estimates;
  both.insert(both.end(), b.estimates.begin(), b.estimates.end());
  return evaluate_all(gt, both, nullptr);
}

// A job initialised with a map file and nothing else: its places are the file's.
Status init_with_map(const std::string& map, std::initializer_list<const char*> overrides,
                     ReplayJob* job) {
  ReplayOptions opt;
  opt.sequence = kClip.c_str();
  opt.progress = false;
  opt.map_in_path = map.c_str();
  RGBDTAM_RETURN_IF_ERROR(read_params_file(kConfig.c_str(), &opt.params));
  for (const char* o : overrides) RGBDTAM_RETURN_IF_ERROR(set_param(o, "test", &opt.params));
  return job->init(opt);
}

class MapFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::make_temp_dir("map_file");
    first_half_ = dir_ + "/first";
    second_half_ = dir_ + "/second";
    map_ = dir_ + "/clip.map";
    ASSERT_TRUE(testing::cut_frames(kClip, first_half_, 25, 25));
    ASSERT_TRUE(testing::cut_frames(kClip, second_half_, 0, 25));
    first_ =
        testing::replay_and_evaluate(first_half_, kConfig, {}, nullptr, {nullptr, map_.c_str()});
    ASSERT_TRUE(first_.ran) << first_.status.message();
  }
  std::string dir_, first_half_, second_half_, map_;
  testing::ReplayOutcome first_;
};

TEST_F(MapFile, ASecondSessionIsFoundInTheFirstOnesMapAndReportsPosesInItsWorld) {
  const auto second =
      testing::replay_and_evaluate(second_half_, kConfig, {}, nullptr, {map_.c_str(), nullptr});
  ASSERT_TRUE(second.ran) << second.status.message();
  const EvaluationReport together = evaluate_together(first_, second);
  std::printf(
      "clip in two sessions: found at frame %d of the second; ATE of both under one "
      "alignment %.2f cm over %d poses\n",
      second.found_in_map_at_frame, together.ate.rmse_m * 100, together.ate.compared);
  EXPECT_GE(second.found_in_map_at_frame, 0);
  EXPECT_LE(second.found_in_map_at_frame, 2);
  EXPECT_EQ(second.report.false_valid.count, 0);
  EXPECT_EQ(second.counters.resets, 0u);
  ASSERT_TRUE(together.ate_ok);
  EXPECT_LT(together.ate.rmse_m, 0.012);

  // Without the map the second session has a world of its own: the check above can fail.
  const auto alone = testing::replay_and_evaluate(second_half_, kConfig);
  const EvaluationReport apart = evaluate_together(first_, alone);
  std::printf("... without the map: %.2f cm\n", apart.ate.rmse_m * 100);
  EXPECT_GT(apart.ate.rmse_m, 3 * together.ate.rmse_m);
}

TEST_F(MapFile, LocaliseModeKeepsTheMapsPlacesWhereTheyWere) {
  const std::vector<uint8_t> before = bytes_of(map_);
  // Twice round the clip, so that revisits correct the map while it is localised in.
  const std::string twice = dir_ + "/twice";
  ASSERT_TRUE(testing::concatenate(kClip, kClip, twice, 0.5));
  // Jobs are large (their latency records): on the heap.
  auto loaded = std::make_unique<ReplayJob>();
  ASSERT_TRUE(init_with_map(map_, {"map.mode=localise"}, loaded.get()).is_ok());
  ReplayOptions opt;
  opt.sequence = twice.c_str();
  opt.progress = false;
  opt.map_in_path = map_.c_str();
  ASSERT_TRUE(read_params_file(kConfig.c_str(), &opt.params).is_ok());
  ASSERT_TRUE(set_param("map.mode=localise", "test", &opt.params).is_ok());
  auto job = std::make_unique<ReplayJob>();
  ASSERT_TRUE(job->init(opt).is_ok());
  while (job->step()) {
  }
  ASSERT_TRUE(job->finish().is_ok());
  const PlaceStore& kept = job->system().places();
  const PlaceStore& file = loaded->system().places();
  ASSERT_EQ(kept.kept(), file.size());
  for (int i = 0; i < file.size(); ++i) {
    EXPECT_EQ(kept.in_order(i).keyframe_id, file.in_order(i).keyframe_id);
    EXPECT_EQ((kept.in_order(i).T_w_k.translation() - file.in_order(i).T_w_k.translation()).norm(),
              0.0);
  }
  EXPECT_GT(kept.size(), file.size());  // the session's own keyframes came and went beside them
  EXPECT_EQ(bytes_of(map_), before);
}

TEST_F(MapFile, DamagedOrMismatchedFilesAreRefusedWithTheReason) {
  const std::vector<uint8_t> good = bytes_of(map_);
  ASSERT_GT(good.size(), 1000u);
  // What the file says of itself, checked before anything is loaded.
  auto refusal = [&](const std::vector<uint8_t>& bytes) {
    MapFileInfo info;
    const Status s = read_map_info(bytes.data(), bytes.size(), &info);
    return std::string(s.is_ok() ? "" : s.message());
  };
  // What the run needs of it, checked when it loads.
  auto load_refusal = [&](std::initializer_list<const char*> overrides) {
    auto job = std::make_unique<ReplayJob>();
    const Status s = init_with_map(map_, overrides, job.get());
    return std::string(s.is_ok() ? "" : s.message());
  };
  EXPECT_EQ(refusal(good), "");
  EXPECT_EQ(load_refusal({}), "");
  for (const size_t size :
       {size_t{0}, size_t{7}, size_t{20}, size_t{239}, good.size() / 2, good.size() - 1}) {
    const std::string why = refusal(std::vector<uint8_t>(good.begin(), good.begin() + size));
    EXPECT_FALSE(why.empty()) << size;
    std::printf("cut to %zu bytes: %s\n", size, why.c_str());
  }
  std::mt19937 random(7);
  for (int i = 0; i < 200; ++i) {
    std::vector<uint8_t> flipped = good;
    flipped[random() % flipped.size()] ^= static_cast<uint8_t>(1u << (random() % 8));
    EXPECT_NE(refusal(flipped).find("checksum mismatch"), std::string::npos);
  }
  // Issue 35, item 5: values out of range are damage even under a valid checksum.
  auto resealed = [](std::vector<uint8_t> bytes, size_t at, const void* value, size_t n) {
    std::memcpy(&bytes[at], value, n);
    uint32_t h = 2166136261u;  // the file's FNV-1a
    for (size_t i = 0; i + 4 < bytes.size(); ++i) h = (h ^ bytes[i]) * 16777619u;
    std::memcpy(&bytes[bytes.size() - 4], &h, 4);
    return bytes;
  };
  constexpr size_t kNextKeyframeIdAt = 76, kFirstPlaceXAt = 240 + 4 + 8 + 32;
  const uint32_t last_id = 0xFFFFFFFFu;
  EXPECT_NE(refusal(resealed(good, kNextKeyframeIdAt, &last_id, 4)).find("next keyframe id"),
            std::string::npos);
  for (const double far : {1e300, 2e4, static_cast<double>(INFINITY)}) {
    write_bytes(map_, resealed(good, kFirstPlaceXAt, &far, 8));
    EXPECT_EQ(refusal(bytes_of(map_)), "") << "the header is whole";
    EXPECT_NE(load_refusal({}).find("place 0 is damaged"), std::string::npos) << far;
  }
  write_bytes(map_, good);
  std::vector<uint8_t> newer = good;
  newer[8] = 2;
  EXPECT_NE(refusal(newer).find("format version 2; this build reads version 1"), std::string::npos);
  EXPECT_NE(refusal(bytes_of(testing::source_path("data/vocabulary/tum-k10-l4.voc")))
                .find("not an rgbdtam map file"),
            std::string::npos);
  EXPECT_NE(load_refusal({"camera.fx=500"}).find("another camera"), std::string::npos);
  const std::string small = load_refusal({"loop.features=50"});
  EXPECT_NE(small.find("loop.features is 50: set it to at least"), std::string::npos) << small;
  std::printf("%s\n%s\n", refusal(newer).c_str(), small.c_str());
}

TEST_F(MapFile, AWriterKilledAtAnyInstantLeavesAMapThatLoads) {
  // The map of the whole clip replaces the first half's, again and again, killed at random
  // instants; and once with a file-size limit, as on a full disk.
  auto job = std::make_unique<ReplayJob>();
  ASSERT_TRUE(init_with_map(map_, {}, job.get()).is_ok());
  while (job->step()) {
  }
  ASSERT_TRUE(job->finish().is_ok());
  std::mt19937 random(11);
  const std::vector<uint8_t> first_map = bytes_of(map_);
  // Kill instants spread over three writes' time on this machine (natively or under qemu).
  const std::string timing = dir_ + "/timing.map";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(save_map_file(timing.c_str(), job->system(), "test").is_ok());
  const auto write_us =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0)
          .count();
  // The first kill comes before the writer starts and the second after its first write, so
  // both maps are seen whatever the scheduler does; the others at random instants.
  int old_map = 0, new_map = 0;
  for (int i = 0; i < 60; ++i) {
    write_bytes(map_, first_map);
    int start[2], written[2];
    ASSERT_EQ(pipe(start), 0);
    ASSERT_EQ(pipe(written), 0);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      char go = 0;
      if (read(start[0], &go, 1) != 1) _exit(1);
      for (;;) {
        (void)save_map_file(map_.c_str(), job->system(), "test");
        if (write(written[1], "w", 1) != 1) _exit(1);
      }
    }
    if (i > 0) {
      ASSERT_EQ(write(start[1], "g", 1), 1);
    }
    if (i == 1) {
      char done = 0;
      ASSERT_EQ(read(written[0], &done, 1), 1);
    } else if (i > 1) {
      usleep(static_cast<useconds_t>(random() % (3 * write_us + 1)));
    }
    kill(child, SIGKILL);
    for (int fd : {start[0], start[1], written[0], written[1]}) close(fd);
    int status = 0;
    waitpid(child, &status, 0);
    // Whole, by its checksum: one of the two maps, never a mixture or a part.
    const std::vector<uint8_t> on_disk = bytes_of(map_);
    MapFileInfo info;
    const Status s = read_map_info(on_disk.data(), on_disk.size(), &info);
    ASSERT_TRUE(s.is_ok()) << "after kill " << i << ": " << s.message();
    ++(on_disk == first_map ? old_map : new_map);
  }
  std::printf("killed 60 times: the first map on disk %d times, the new one %d\n", old_map,
              new_map);
  EXPECT_GT(old_map, 0);
  EXPECT_GT(new_map, 0);
  ASSERT_TRUE(save_map_file(map_.c_str(), job->system(), "test").is_ok());
  auto check = std::make_unique<ReplayJob>();
  ASSERT_TRUE(init_with_map(map_, {}, check.get()).is_ok());
  EXPECT_EQ(check->loaded_map().places, static_cast<uint32_t>(job->system().places().size()));
  const size_t first_size = first_map.size();

  const std::vector<uint8_t> before = bytes_of(map_);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{first_size / 2, first_size / 2};
    setrlimit(RLIMIT_FSIZE, &limit);
    const Status s = save_map_file(map_.c_str(), job->system(), "test");
    _exit(s.is_ok() ? 0 : 3);
  }
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 3);
  EXPECT_EQ(bytes_of(map_), before);
}

}  // namespace
}  // namespace rgbdtam

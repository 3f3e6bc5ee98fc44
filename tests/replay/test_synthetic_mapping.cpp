// Multi-view mapping on a synthetic sequence with exact ground truth: a textured wall at 6 m,
// beyond the simulated sensor's 4 m range (no depth there), and a near box with valid depth.
// The camera glides diagonally right and up at 45 cm/s (both edge orientations get parallax),
// so the box leaves the view and tracking must go on with the wall's multi-view points alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "rgbdtam/core/canny.hpp"
#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/runtime/slam_system.hpp"
#include "synthetic_scene.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

constexpr double kFps = 30.0;
constexpr int kFrames = 90;
constexpr double kWallZ = 6.0;

testing::SyntheticScene far_wall_scene(double max_depth_m) {
  testing::SyntheticScene s;
  s.with_room = false;
  s.back_wall_z_m = kWallZ;
  s.max_depth_m = max_depth_m;
  s.diagonal_path = true;
  return s;
}

struct KeyframeScore {
  int wall_edges = 0;   // Canny edge pixels on the wall that qualify as seeds
  int wall_mapped = 0;  // of those, pixels with a multi-view depth
  double median_relative_error = 0;
};

// Scores each keyframe's map against the renderer's exact depth.
class WallScorer : public MapSink {
 public:
  void on_keyframe_map(int64_t timestamp_ns, const SE3&, const PinholeIntrinsics& k,
                       const FixedVector<FusedPixel>& pixels) override {
    const testing::SyntheticScene truth = far_wall_scene(100.0);
    const int index = static_cast<int>(std::lround(timestamp_ns * 1e-9 * kFps));
    const testing::SyntheticFrame f = truth.render(truth.camera_at(index / kFps));
    const int w = k.width_px, h = k.height_px;
    ImageF gray;
    ImageU8 edges;
    gray.allocate(w, h);
    edges.allocate(w, h);
    for (int i = 0; i < w * h; ++i) gray.data()[i] = f.gray[static_cast<size_t>(i)] / 255.f;
    CannyDetector canny;
    canny.allocate(w, h);
    const TrackerOptions t;
    canny.detect(gray, t.canny_low, t.canny_high, &edges);
    const MultiViewOptions mv;
    auto on_wall = [&](int x, int y) {
      return f.depth[static_cast<size_t>(y * w + x)] / truth.depth_factor > kWallZ - 1.0;
    };
    KeyframeScore score;
    for (int y = mv.border_px; y < h - mv.border_px; ++y) {
      for (int x = mv.border_px; x < w - mv.border_px; ++x) {
        const float g = 0.5f * (std::fabs(gray.at(x + 1, y) - gray.at(x - 1, y)) +
                                std::fabs(gray.at(x, y + 1) - gray.at(x, y - 1)));
        if (edges.at(x, y) != 0 && g >= mv.min_gradient && on_wall(x, y)) ++score.wall_edges;
      }
    }
    std::vector<double> errors;
    for (const FusedPixel& p : pixels) {
      if (p.source != DepthSource::kMultiView || !on_wall(p.x, p.y)) continue;
      const double z = f.depth[static_cast<size_t>(p.y * w + p.x)] / truth.depth_factor;
      errors.push_back(std::fabs(1.0 / p.rho - z) / z);
    }
    score.wall_mapped = static_cast<int>(errors.size());
    if (!errors.empty()) {
      std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
      score.median_relative_error = errors[errors.size() / 2];
    }
    scores.push_back(score);
  }
  std::vector<KeyframeScore> scores;
};

TEST(SyntheticMapping, FarWallBeyondSensorRangeIsMappedAndTrackingContinuesOnIt) {
  const testing::SyntheticScene scene = far_wall_scene(4.0);
  Params p;
  p.camera = scene.camera;
  p.sensor.depth_factor = scene.depth_factor;
  p.sensor.depth_range = DepthRange{0.3, 4.0};
  p.sensor.disparity_sigma_px = 0.1;  // the synthetic sensor is exact
  p.map_enabled = true;
  p.map_seeds = 50000;  // every qualifying edge pixel becomes a seed

  WallScorer scorer;
  SlamSystem slam;
  ASSERT_TRUE(slam.init(
                      p, [] { return int64_t{0}; }, &scorer)
                  .is_ok());
  ASSERT_TRUE(slam.start().is_ok());
  const auto& frames = scene.render_path(kFrames, kFps);
  const SE3 T_w0 = scene.camera_at(0.0);
  double worst_m = 0.0, worst_without_box_m = 0.0;
  int tracked = 0, frames_without_box = 0;
  for (int i = 0; i < kFrames; ++i) {
    const testing::SyntheticFrame& f = frames[static_cast<size_t>(i)];
    const PoseEstimate pose = slam.process(f.as_sensor_frame(scene.camera, i, kFps));
    if ((pose.flags & kPoseValid) == 0) continue;
    ++tracked;
    const SE3 truth = T_w0.inverse() * scene.camera_at(i / kFps);
    const double err = (truth.inverse() * pose.T_w_c).translation().norm();
    worst_m = std::max(worst_m, err);
    if (std::all_of(f.depth.begin(), f.depth.end(), [](uint16_t d) { return d == 0; })) {
      ++frames_without_box;
      worst_without_box_m = std::max(worst_without_box_m, err);
    }
  }
  slam.finish();
  // The first frames, before a velocity is known, may be ambiguous: the camera could then be
  // anywhere within 10 cm (3 m/s over a frame), and on the wall's checker, where the tracker's
  // edge points lie, another pose within that fits about as well. Every frame after is tracked.
  EXPECT_GE(tracked, kFrames - 2);
  EXPECT_GT(frames_without_box, 10) << "the near box must leave the view";
  // 1.35 m travelled; the last frames see nothing but the wall beyond the sensor's range.
  EXPECT_LT(worst_m, 0.02);
  ASSERT_GT(scorer.scores.size(), 2u);
  for (size_t k = 0; k < scorer.scores.size(); ++k) {
    const KeyframeScore& s = scorer.scores[k];
    std::printf("keyframe %zu: %d of %d wall edge pixels mapped (%.0f %%), median error %.2f %%\n",
                k, s.wall_mapped, s.wall_edges, 100.0 * s.wall_mapped / std::max(1, s.wall_edges),
                100.0 * s.median_relative_error);
    EXPECT_LE(s.median_relative_error, 0.02) << "keyframe " << k;
    // Measured 86-94 % per keyframe.
    EXPECT_GE(s.wall_mapped * 5, s.wall_edges * 4) << "keyframe " << k;
  }
  std::printf("tracking: worst error %.1f mm; %.1f mm over the %d frames without the box\n",
              worst_m * 1e3, worst_without_box_m * 1e3, frames_without_box);
}

// Stalls the mapper's thread at its first finished keyframe, as a board too slow for it would,
// until the test releases it: the frames sent meanwhile back up in the mapper's queue whatever
// the scheduler does.
class StallingSink : public MapSink {
 public:
  void on_keyframe_map(int64_t, const SE3&, const PinholeIntrinsics&,
                       const FixedVector<FusedPixel>&) override {
    std::unique_lock<std::mutex> lock(mutex_);
    if (maps_++ == 0) released_changed_.wait(lock, [this] { return released_; });
  }
  void release() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      released_ = true;
    }
    released_changed_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable released_changed_;
  bool released_ = false;
  int maps_ = 0;
};

TEST(SyntheticMapping, AMapperBehindSkipsFramesToCatchUpAndTheTrackerNeverWaits) {
  // The wall within the sensor's range: tracking needs no map from the mapper.
  const testing::SyntheticScene scene = far_wall_scene(10.0);
  Params p = testing::synthetic_params(scene);
  p.map_enabled = true;
  p.map_threaded = true;
  p.map_frames_per_keyframe = 2;  // the first map, and the stall, come early
  // Released, the mapper finds seven frames behind the one it stalled on: it is late (half its
  // queue or more waiting) for the next four, at most one of which can be a keyframe's.
  p.map_queue_frames = 8;
  StallingSink sink;
  SlamSystem slam;
  ASSERT_TRUE(slam.init(p, monotonic_ns, &sink).is_ok());
  ASSERT_TRUE(slam.start().is_ok());
  constexpr int kStalledFrames = 45;
  const auto& frames = scene.render_path(kStalledFrames, kFps);
  int tracked = 0;
  for (int i = 0; i < kStalledFrames; ++i) {
    const PoseEstimate pose =
        slam.process(frames[static_cast<size_t>(i)].as_sensor_frame(scene.camera, i, kFps));
    tracked += (pose.flags & kPoseValid) != 0 ? 1 : 0;
  }
  // Every frame was tracked while the mapper stalled: its first map comes within the first
  // twenty frames, and the rest fill its queue (or, had its thread not yet run, the first ones
  // do), so it now finds its queue full and catches up.
  sink.release();
  slam.finish();
  const MappingCounters& m = slam.mapper().counters();
  const TrackingCounters& c = slam.tracking().counters();
  EXPECT_EQ(tracked, kStalledFrames);
  EXPECT_GT(m.frames_skipped_late, 0u) << "the mapper must catch up by skipping frames";
  // Every keyframe offered reaches a map or is counted as dropped at the queue.
  EXPECT_EQ(m.keyframes_mapped + c.mapper_dropped_keyframes, c.keyframes);
  std::printf(
      "stalled mapper: %u frames observed, %u skipped to catch up, %u dropped at the "
      "queue (%u keyframes); %u of %u keyframes mapped\n",
      m.frames_observed, m.frames_skipped_late, c.mapper_dropped_frames, c.mapper_dropped_keyframes,
      m.keyframes_mapped, c.keyframes);
}

}  // namespace
}  // namespace rgbdtam

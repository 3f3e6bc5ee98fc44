// The full fr1_xyz sequence (798 frames) and the first 200 frames of the hand-held fr3_teddy,
// where the machine has them: the accuracy and the honesty the tracking issues ask for.
// Skipped elsewhere, since the repository holds only a clip.
#include <gtest/gtest.h>

#include "replay_runner.hpp"
#include "stress_variants.hpp"
#include "test_paths.hpp"

#ifdef RGBDTAM_COUNT_ALLOCATIONS
#include "allocation_counting.hpp"
#endif

namespace rgbdtam {
namespace {

// Each replay of the file, and where the build counts allocations (static, unsanitized) none
// after init: relocalising, closing loops, restarting, with stores that recycle.
testing::ReplayOutcome replay(const std::string& seq, const std::string& config,
                              std::initializer_list<const char*> overrides = {}) {
  testing::ReplayOutcome out = testing::replay_and_evaluate(seq, config, overrides);
  if (out.ran && out.allocations_after_init >= 0) {
    std::printf("%ld allocations after init\n", out.allocations_after_init);
    EXPECT_EQ(out.allocations_after_init, 0) << seq << ": heap allocations after init";
  }
  return out;
}

// What autopilots fuse: the reported covariance against the real frame-to-frame error. A
// consistent 6-dof covariance gives a mean NEES of 6; within a factor of two either way.
void expect_consistent_covariance(const testing::ReplayOutcome& out, const char* label) {
  EXPECT_GT(out.report.nees.pairs, 100) << label;
  EXPECT_GE(out.report.nees.mean, 3.0) << label;
  EXPECT_LE(out.report.nees.mean, 12.0) << label;
  std::printf("%s: frame-to-frame NEES mean %.2f, median %.2f over %d pairs\n", label,
              out.report.nees.mean, out.report.nees.median, out.report.nees.pairs);
}

// The shipped config (mapping on) over all frames. The mapping issue: the fused multi-view map
// must not cost accuracy against tracking alone. One run against one is a coin toss (a change
// that should not matter, such as a Canny threshold 0.5 higher, moves either by up to 0.07 cm),
// so this pair may differ by that much; tools/mapping_vs_tracking.sh compares the means of six
// such pairs, within 0.03 cm. Where the map matters, beyond the sensor's range, the synthetic
// far-wall test shows it.
TEST(FullSequence, Fr1XyzAllFramesWithinOnePointTwoCentimetresAndMappingCostsNoAccuracy) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const std::string config = testing::source_path("config/tum_fr1.conf");
  const auto out = replay(seq, config);
  const auto alone = replay(seq, config, {"map.enabled=false"});
  ASSERT_TRUE(out.ran && alone.ran);
  // The health checks stay quiet on the easy sequence: nothing lost, nothing retried away.
  EXPECT_EQ(out.counters.lost, 0u);
  EXPECT_EQ(out.report.false_valid.count, 0);
  EXPECT_DOUBLE_EQ(out.report.coverage.fraction(), 1.0);
  ASSERT_TRUE(out.report.ate_ok && alone.report.ate_ok);
  EXPECT_LE(out.report.ate.rmse_m, 0.012);
  EXPECT_LE(out.report.ate.rmse_m, alone.report.ate.rmse_m + 0.0007);
  std::printf(
      "fr1_xyz: ATE %.3f cm over %d poses (%.3f cm without mapping), RPE %.2f cm/s "
      "%.3f deg/s\n",
      out.report.ate.rmse_m * 100, out.report.ate.compared, alone.report.ate.rmse_m * 100,
      out.report.rpe.trans_rmse_m * 100, out.report.rpe.rot_rmse_deg);
  expect_consistent_covariance(out, "fr1_xyz");
}

// The robust-tracking issue's development sequence: hand-held, fast, around a teddy bear.
TEST(FullSequence, Fr3TeddyWithinOnePointFiveCentimetresAndNeverFalseValid) {
  const std::string seq = testing::fr3_teddy_200();
  if (seq.empty()) GTEST_SKIP() << "fr3_teddy_200 not present on this machine";
  const auto out = replay(seq, testing::source_path("config/tum_fr3.conf"));
  testing::expect_tracked_or_lost(out, "fr3_teddy_200", 0.95);
  ASSERT_TRUE(out.report.ate_ok);
  EXPECT_LE(out.report.ate.rmse_m, 0.015);
  expect_consistent_covariance(out, "fr3_teddy_200");
}

// Its stress variants: blurred along the true motion, and three times faster. Tracked or
// reported lost, never a wrong pose reported as tracked.
TEST(FullSequence, Fr3TeddyBlurredOrFasterIsNeverFalseValid) {
  const std::string seq = testing::fr3_teddy_200();
  if (seq.empty()) GTEST_SKIP() << "fr3_teddy_200 not present on this machine";
  const std::string config = testing::source_path("config/tum_fr3.conf");
  const std::string dir = testing::make_temp_dir("teddy_variants");
  ASSERT_TRUE(testing::blur_sequence(seq, dir + "/blur", config, 30.0));
  ASSERT_TRUE(testing::decimate_sequence(seq, dir + "/x3", 3));
  for (const char* variant : {"/blur", "/x3"}) {
    testing::expect_tracked_or_lost(replay(dir + variant, config),
                                    std::string("fr3_teddy_200") + variant, 0.9);
  }
}

// With the Raspberry Pi 4's profile (board/raspberry-pi-4: tracked down to 320x240, 4 000 points,
// 4 000 seeds, 24 keyframes), two of teddy's frames soon after map reuse took an earlier keyframe
// up again fit it badly and the keyframe it replaced well. They are tracked against the one left
// from the prediction before any wider search: on the Pi 4 a wider search (tens of trackings)
// makes the frame and the next miss their deadlines.
TEST(FullSequence, Fr3TeddyOnThePi4sProfileFramesLostByTheKeyframeTakenUpNeedNoWiderSearch) {
  const std::string seq = testing::fr3_teddy_200();
  if (seq.empty()) GTEST_SKIP() << "fr3_teddy_200 not present on this machine";
  // Each depth image as if taken with its colour, and each image's rows as if taken at once: so,
  // on this recording, one frame fails as the keyframe is taken up (tracked from where each was
  // taken, row by row, none does, and there is nothing to check).
  const auto out = replay(seq, testing::source_path("config/tum_fr3.conf"),
                          {"tracker.iterations_l0=0", "tracker.photometric_points=4000",
                           "map.seeds=4000", "map.keyframe_pool=24", "depth.at_its_instant=false",
                           "camera.readout_ms=0", "depth.readout_ms=0"});
  testing::expect_tracked_or_lost(out, "fr3_teddy_200, the Pi 4's profile", 1.0);
  std::printf("%u recovered against the keyframe left, %u wider searches\n",
              out.counters.recovered_by_left_keyframe, out.counters.wider_searches);
  EXPECT_GE(out.counters.recovered_by_left_keyframe, 1u);
  EXPECT_LT(out.counters.wider_searches, out.counters.retried)
      << "every frame that failed ran a wider search";
  EXPECT_EQ(out.counters.recovered_by_last_frame, 0u) << "a keyframe built on the tracker's thread";
}

// The local window (issue 33; loop.window, on by default) on teddy at twice the speed, which
// drifts: each new keyframe is measured again against the earlier keyframe that sees most of
// it, and the map is refined with it; the corrections are blended into the poses sent. Over
// eight copies dithered by one depth unit, live ATE was 0.85 cm mean (0.73-1.09) with the window
// and 1.43 (1.11-1.60) without. (At three times the speed it was worse: docs/loop-closure.md.)
// One recording is one draw of the sensor's noise, and the difference is the copies' mean: a
// change tried on the keyframes' depth, which moved teddy's by a millisecond's motion, turned the
// recording alone from 0.68 against 0.72 cm to 0.65 against 0.63. So three copies, as
// tools/dither_ensemble.sh makes them (seeds 1-3), each tracked with the window and without.
TEST(FullSequence, Fr3TeddyTwiceAsFastDriftsLessWithTheLocalWindow) {
  const std::string seq = testing::fr3_teddy_200();
  if (seq.empty()) GTEST_SKIP() << "fr3_teddy_200 not present on this machine";
  const std::string config = testing::source_path("config/tum_fr3.conf");
  const std::string dir = testing::make_temp_dir("teddy_x2_window");
  ASSERT_TRUE(testing::decimate_sequence(seq, dir + "/x2", 2));
  double window_cm = 0.0, without_cm = 0.0;
  constexpr unsigned kCopies = 3;
  for (unsigned seed = 1; seed <= kCopies; ++seed) {
    const std::string copy = dir + "/x2_" + std::to_string(seed);
    ASSERT_TRUE(testing::dither_depth(dir + "/x2", copy, config, seed));
    const auto window = replay(copy, config, {"loop.window=true"});
    const auto without = replay(copy, config, {"loop.window=false"});
    ASSERT_TRUE(window.ran && without.ran);
    std::printf(
        "teddy x2, copy %u: live ATE %.2f cm with the window (%u window edges, %u corrections, "
        "%u blended), %.2f without\n",
        seed, 100 * window.report.ate.rmse_m, window.loop.window_edges,
        window.counters.loop_corrections, window.counters.blended_corrections,
        100 * without.report.ate.rmse_m);
    EXPECT_GE(window.loop.window_edges, 5u);
    EXPECT_EQ(without.loop.window_edges, 0u);
    EXPECT_GE(window.counters.loop_corrections, 1u);
    testing::expect_tracked_or_lost(window, "fr3_teddy_200 x2 with the window", 0.99);
    EXPECT_EQ(window.counters.withheld, 0u);
    window_cm += 100 * window.report.ate.rmse_m / kCopies;
    without_cm += 100 * without.report.ate.rmse_m / kCopies;
  }
  std::printf("teddy x2, %u copies: live ATE %.2f cm mean with the window, %.2f without\n", kCopies,
              window_cm, without_cm);
  EXPECT_LT(window_cm, without_cm);
}

// The loop-closure issue's kidnapping: 100 frames (3.3 s) cut from fr1_xyz, as a long USB stall
// would. The first frame after the gap is looked up in the map and tracking resumes there.
TEST(FullSequence, Fr1XyzWithAHundredFramesCutIsRelocalisedAtOnce) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const std::string dir = testing::make_temp_dir("fr1_cut100");
  ASSERT_TRUE(testing::cut_frames(seq, dir + "/cut", 300, 100));
  const auto out = replay(dir + "/cut", testing::source_path("config/tum_fr1.conf"));
  ASSERT_TRUE(out.ran);
  EXPECT_GE(out.counters.relocalised, 1u);
  EXPECT_LE(out.counters.lost, 10u) << "relocalised within 10 frames of the gap";
  EXPECT_EQ(out.counters.resets, 0u) << "relocalised, not restarted";
  testing::expect_tracked_or_lost(out, "fr1_xyz, frames 300-399 cut", 0.9);
  EXPECT_LE(out.report.ate.rmse_m, 0.015);
}

// Kidnapping at several places of fr1_xyz, each length of the loop-closure issue once: every
// time the tracker finds the map again within 10 frames of the gap's end (relocalised, or
// tracking through where the camera came back to its last view), and never restarts.
TEST(FullSequence, Fr1XyzCutAnywhereIsFoundAgainWithinTenFrames) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const std::string dir = testing::make_temp_dir("fr1_cuts");
  // (100 frames at 300: the test above.)
  const struct { int first, count; } cuts[] = {{450, 30}, {150, 60}, {150, 150}};
  for (const auto& cut : cuts) {
    const std::string name =
        dir + "/cut" + std::to_string(cut.first) + "_" + std::to_string(cut.count);
    ASSERT_TRUE(testing::cut_frames(seq, name, cut.first, cut.count));
    const auto out = replay(name, testing::source_path("config/tum_fr1.conf"));
    ASSERT_TRUE(out.ran);
    const std::string label =
        std::to_string(cut.count) + " frames cut at " + std::to_string(cut.first);
    EXPECT_LE(out.counters.lost, 10u) << label;
    EXPECT_EQ(out.counters.resets, 0u) << label << ": found again, not restarted";
    testing::expect_tracked_or_lost(out, label, 0.95);
    EXPECT_LE(out.report.ate.rmse_m, 0.015) << label;
  }
}

// Small loop corrections blended into the poses sent (issue 33): with corrections from 5 mm,
// fr1_xyz closes eleven, each under the 5 cm a jump may be. Blended in, they step no reset
// counter and withhold nothing; the map is the same as with every correction sent at once, and
// the poses sent differ from those only while a correction is taken up, by less than one.
TEST(FullSequence, Fr1XyzSmallCorrectionsAreBlendedIntoThePosesSentWithoutAReset) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const std::string config = testing::source_path("config/tum_fr1.conf");
  const auto blended =
      replay(seq, config, {"loop.min_correction=0.005", "loop.min_correction_angle=0.2"});
  const auto at_once =
      replay(seq, config,
             {"loop.min_correction=0.005", "loop.min_correction_angle=0.2", "loop.blend_rate=0"});
  ASSERT_TRUE(blended.ran && at_once.ran);
  std::printf("%u corrections, %u blended; live ATE %.3f cm blended, %.3f at once\n",
              blended.counters.loop_corrections, blended.counters.blended_corrections,
              100 * blended.report.ate.rmse_m, 100 * at_once.report.ate.rmse_m);
  EXPECT_GE(blended.counters.loop_corrections, 5u);
  EXPECT_EQ(blended.counters.blended_corrections, blended.counters.loop_corrections);
  EXPECT_EQ(at_once.counters.blended_corrections, 0u);
  EXPECT_EQ(at_once.counters.loop_corrections, blended.counters.loop_corrections);
  EXPECT_EQ(blended.counters.withheld, 0u);
  EXPECT_EQ(blended.report.false_valid.count, 0);
  EXPECT_DOUBLE_EQ(blended.final_report.ate.rmse_m, at_once.final_report.ate.rmse_m)
      << "tracking and the map are the same: only the poses sent differ";
  ASSERT_EQ(blended.estimates.size(), at_once.estimates.size());
  int differing = 0;
  for (size_t i = 0; i < blended.estimates.size(); ++i) {
    const double d =
        (blended.estimates[i].T_w_c.translation() - at_once.estimates[i].T_w_c.translation())
            .norm();
    EXPECT_LE(d, 0.05) << "frame " << i;
    differing += d > 1e-9 ? 1 : 0;
  }
  EXPECT_GT(differing, 0);
  EXPECT_LE(differing, static_cast<int>(16 * blended.counters.blended_corrections))
      << "each taken up within 0.5 s";
  EXPECT_LE(blended.report.ate.rmse_m, at_once.report.ate.rmse_m + 0.0005);
}

// Long runs at full stores, in small: the first 400 frames of fr1_xyz, an outage of 1 s, and
// the camera back at the start, with a place store of 32 and a dense pool of 9 so that both
// recycle. The start's dense keyframe has long been recycled, but its place is remembered: the
// first frame after the gap is found there, on a new keyframe, and nothing forgotten comes
// back as a wrong pose.
// Since the depth term's gradients come from each point's patch (issue 32), the first frame
// after the gap is found by the wider basin against the current keyframe (the desk overlaps
// it), before relocalisation is asked; either way it must be found without a restart.
TEST(FullSequence, Fr1XyzBackAtTheStartIsFoundAgainWithoutARestartAfterThePlacesForgot) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const std::string dir = testing::make_temp_dir("fr1_back_to_start");
  ASSERT_TRUE(testing::cut_frames(seq, dir + "/first400", 400, 398));
  ASSERT_TRUE(testing::concatenate(dir + "/first400", seq, dir + "/back", 1.0));
  const auto out = replay(dir + "/back", testing::source_path("config/tum_fr1.conf"),
                          {"loop.places=32", "map.keyframe_pool=9"});
  ASSERT_TRUE(out.ran);
  std::printf("%u places remembered by a store of 32; %u relocalised, %u past the dense pool\n",
              out.loop.keyframes, out.counters.relocalised, out.counters.relocalised_past_the_pool);
  EXPECT_GT(out.loop.keyframes, 32u) << "the place store forgot";
  EXPECT_GE(out.counters.relocalised + out.counters.recovered_by_guesses +
                out.counters.recovered_by_last_frame,
            1u)
      << "found again by the map or by tracking";
  EXPECT_EQ(out.counters.resets, 0u);
  testing::expect_tracked_or_lost(out, "fr1_xyz 0-399, then 0-797 again", 0.95);
  EXPECT_LE(out.report.ate.rmse_m, 0.015);
}

// Without relocalisation the tracker restarts after the gap where it was, 10-30 cm from the
// truth; the loop module finds the old map again and the pose graph, whose restart edge carries
// no information, moves the new stretch onto it. (After 100 frames cut at 300 the camera is back
// where it was, and tracking resumes without a restart; after 150 at 150 it is not.)
TEST(FullSequence, Fr1XyzARestartJoinsTheMapAtTheNextLoop) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const std::string dir = testing::make_temp_dir("fr1_restart");
  ASSERT_TRUE(testing::cut_frames(seq, dir + "/cut", 150, 150));
  const std::string config = testing::source_path("config/tum_fr1.conf");
  const auto alone = replay(dir + "/cut", config, {"loop.enabled=false"});
  const auto joined = replay(dir + "/cut", config, {"loop.relocalise=false"});
  ASSERT_TRUE(alone.ran && joined.ran);
  EXPECT_EQ(joined.counters.resets, 1u);
  EXPECT_GE(joined.loop.corrections, 1u);
  // Live, the poses after the correction are withheld for the window a consumer differences
  // over, so the jump is never a false-valid pose.
  testing::expect_tracked_or_lost(joined, "restart joined by a loop (live)", 0.9);
  std::printf("final map ATE %.2f cm with the loop, %.2f cm without\n",
              100 * joined.final_report.ate.rmse_m, 100 * alone.report.ate.rmse_m);
  EXPECT_LT(joined.final_report.ate.rmse_m, 0.5 * alone.report.ate.rmse_m);
  EXPECT_LE(joined.final_report.ate.rmse_m, 0.02);
}

}  // namespace
}  // namespace rgbdtam

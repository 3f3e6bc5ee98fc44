// Integrity on repeated textures (issue 32): panels, tiles, brick and shelving walked along fast,
// with and without sensor noise, a person crossing, loop closure on and off. A pose is tracked
// right or reported lost: never false-valid, never misleading. tools/integrity.sh prints the
// whole family's table, these scenes included.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "repeated_scene.hpp"
#include "replay_runner.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

// Which loop closure settings a scene is replayed with: off only where the scene's pose alone is
// the point (the person crossing the shelves), on only where loop closure is what is tested.
enum class Loop { kOff, kOffAndOn, kOn };

// readout_ms: a rolling shutter's readout claimed for both images (0: none, as rendered).
void expect_never_wrong(const char* name, int frames, Loop loops, int readout_ms = 0) {
  testing::RepeatedScene scene;
  ASSERT_TRUE(testing::RepeatedScene::named(name, &scene));
  const std::string dir = testing::make_temp_dir(name) + "/seq";
  ASSERT_TRUE(testing::repeated_sequence(dir, scene, frames));
  const std::string vocabulary =
      "loop.vocabulary=" + testing::source_path("data/vocabulary/tum-k10-l4.voc");
  const std::string colour_readout = "camera.readout_ms=" + std::to_string(readout_ms);
  const std::string depth_readout = "depth.readout_ms=" + std::to_string(readout_ms);
  for (const bool loop : {false, true}) {
    if ((loop && loops == Loop::kOff) || (!loop && loops == Loop::kOn)) continue;
    const testing::ReplayOutcome out = testing::replay_and_evaluate(
        dir, dir + "/camera.conf",
        {loop ? vocabulary.c_str() : "loop.enabled=false", "map.enabled=true",
         colour_readout.c_str(), depth_readout.c_str()});
    ASSERT_TRUE(out.ran) << out.status.message();
    std::printf(
        "%s, loop %s: %u of %u tracked, false-valid %d of %d, misleading %d, NEES mean %.2f\n",
        name, loop ? "on" : "off", out.counters.tracked, out.counters.frames,
        out.report.false_valid.count, out.report.false_valid.checked, out.report.nees.misleading,
        out.report.nees.mean);
    EXPECT_EQ(out.report.false_valid.count, 0) << name << (loop ? " with" : " without") << " loop";
    EXPECT_EQ(out.report.nees.misleading, 0) << name;
    if (out.report.nees.pairs > 0) {
      EXPECT_LE(out.report.nees.mean, 12.0) << name;
    }
  }
}

TEST(RepeatedScenes, PanelsAtArmsLengthAt30HzAreTrackedOrLostNeverWrong) {
  expect_never_wrong("panels60_d05_30hz", 90, Loop::kOffAndOn);
}

// With loop closure on, a relocalisation onto a look-alike metre-wide panel is not sent within
// the window in which the autopilot differences poses (before: 11 false-valid in these frames).
// Panels at arm's length at 10 Hz: frames are lost, and after two lost frames the camera can be
// 0.3 m further along the wall, wider than the search for other minima can probe. The frame
// after them is beyond the search, not a pose one panel seam off (before: 14.5 cm off over
// 0.5 s, sent as valid).
TEST(RepeatedScenes, PanelsAt10HzAfterALossAreNeverWrong) {
  expect_never_wrong("panels60_d05_10hz_noisy", 80, Loop::kOff);
}

TEST(RepeatedScenes, MetrePanelsAt2mWithAPersonCrossingAreNeverWrong) {
  expect_never_wrong("panels100_d2_30hz_person", 90, Loop::kOn);
}

TEST(RepeatedScenes, FifteenCentimetreTilesAt10HzWithSensorNoiseAreNeverWrong) {
  expect_never_wrong("tiles15_d06_10hz_noisy", 40, Loop::kOffAndOn);
}

TEST(RepeatedScenes, BrickWithSensorNoiseIsNeverWrong) {
  expect_never_wrong("brick25_d1_30hz_noisy", 60, Loop::kOffAndOn);
}

// A config that claims a rolling shutter the camera does not have (these walls are rendered at
// once): the rows are placed by a motion that did not bend them. Tracking places them by the
// motion from the last frame only when that frame was itself tracked on from its own; following
// a pose from before a lost frame let 5 poses out wrong here (0.5 s of motion 10 cm off).
TEST(RepeatedScenes, BrickAt10HzWithAReadoutItDoesNotHaveIsNeverWrong) {
  expect_never_wrong("brick25_d1_10hz", 50, Loop::kOff, 20);
}

TEST(RepeatedScenes, APersonCrossingShelvesDoesNotDragThePose) {
  expect_never_wrong("shelving50_d1_30hz_person", 90, Loop::kOff);
}

}  // namespace
}  // namespace rgbdtam

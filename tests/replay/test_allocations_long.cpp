// No heap allocation after init while relocalising or closing a loop, on the full fr1_xyz with
// frames cut (long: two full-sequence replays; where the machine has the sequence).
#include <gtest/gtest.h>

#include "allocation_counting.hpp"
#include "stress_variants.hpp"

namespace rgbdtam {
namespace {

TEST(Allocations, NoneWhileRelocalisingOrClosingALoop) {
  // fr1_xyz with 150 frames cut: relocalised at once; or, without relocalisation, restarted and
  // joined to the map by a loop closure (pose graph, correction adopted, poses withheld).
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const std::string dir = testing::make_temp_dir("alloc_loop");
  ASSERT_TRUE(testing::cut_frames(seq, dir + "/cut", 150, 150));
  for (const char* mode : {"loop.relocalise=true", "loop.relocalise=false"}) {
    ReplayJob job;
    const long calls = count_allocations_after_init({mode}, &job, dir + "/cut");
    const TrackingCounters& c = job.counters();
    EXPECT_GE(c.relocalised + c.loop_corrections, 1u) << mode << ": nothing exercised";
    EXPECT_EQ(calls, 0) << mode << ": " << g_bytes.load() << " bytes allocated after init";
    std::printf(
        "%s: %u relocalised, %u loop corrections, %u withheld; %ld allocations after "
        "init\n",
        mode, c.relocalised, c.loop_corrections, c.withheld, calls);
  }
}

TEST(Allocations, NoneWhileBothStoresRecycle) {
  // The same cut with a place store of 12 and a dense pool of 9: both wrap, and the loop module
  // drops the edges of forgotten places when its edge store fills.
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "full fr1_xyz not present on this machine";
  const std::string dir = testing::make_temp_dir("alloc_stores");
  ASSERT_TRUE(testing::cut_frames(seq, dir + "/cut", 150, 150));
  ReplayJob job;
  const long calls =
      count_allocations_after_init({"loop.places=12", "map.keyframe_pool=9"}, &job, dir + "/cut");
  const uint32_t forgotten = job.system().places().evicted();
  EXPECT_GT(forgotten, 12u) << "the place store wrapped";
  EXPECT_GT(job.system().tracking().keyframes().recycled(), 9);
  EXPECT_EQ(calls, 0) << g_bytes.load() << " bytes allocated after init";
  std::printf("%u places forgotten, %d dense keyframes recycled; %ld allocations after init\n",
              forgotten, job.system().tracking().keyframes().recycled(), calls);
}

}  // namespace
}  // namespace rgbdtam

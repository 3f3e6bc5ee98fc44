// No heap allocation after init while the place store and the dense pool recycle, on the full
// fr1_xyz with frames cut (long: a full-sequence replay; where the machine has the sequence).
// Relocalising, closing loops and restarting are counted in the full-sequence tests' replays.
#include <gtest/gtest.h>

#include "allocation_counting.hpp"
#include "stress_variants.hpp"

namespace rgbdtam {
namespace {

TEST(Allocations, NoneWhileBothStoresRecycle) {
  // fr1_xyz with 150 frames cut, a place store of 12 and a dense pool of 9: both wrap, and the loop
  // module drops the edges of forgotten places when its edge store fills.
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

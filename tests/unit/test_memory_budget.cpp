// A configuration that needs more memory than the budget is refused at init with the keys that
// size it (its agreement with what init really allocates is in test_allocations).
#include <gtest/gtest.h>

#include <string>

#include "memory_budget.hpp"
#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {
namespace {

TEST(MemoryBudget, ABigPoolIsRefusedWithItsKeyAndTheDefaultFits) {
  Params p;
  uint64_t needed = 0;
  const MemoryBudget board = memory_budget(512);
  EXPECT_EQ(board.bytes, 512ull << 20);
  EXPECT_TRUE(check_memory_budget(p, 0, 0, 0, 0, board, &needed).is_ok());
  EXPECT_EQ(needed, memory_need(p).total());
  p.keyframe_pool_size = 4096;
  const Status s = check_memory_budget(p, 0, 0, 0, 0, board, &needed);
  ASSERT_FALSE(s.is_ok());
  EXPECT_GT(needed, 8000ull << 20) << "thousands of keyframes of megabytes each";
  for (const char* part : {"over the 512 MB budget (memory.budget_mb = 512)",
                           "map.keyframe_pool 4096 x", "lower map.keyframe_pool"}) {
    EXPECT_NE(std::string(s.message()).find(part), std::string::npos) << s.message();
  }
  // A replay keeps a result per listed frame, and a sensor thread its frames: counted too.
  p.keyframe_pool_size = 32;
  EXPECT_FALSE(check_memory_budget(p, 0, 0, 1000, 1'000'000, board, &needed).is_ok());
  EXPECT_TRUE(check_memory_budget(p, 0, 3u << 20, 0, 0, board, &needed).is_ok());
  EXPECT_EQ(needed, memory_need(p).total() + (3u << 20));
  EXPECT_GT(memory_budget(0).bytes, 0u) << "half of this machine's memory";
}

}  // namespace
}  // namespace rgbdtam

// The keyframe pool's policy when full: recycle the oldest keyframe that is neither the
// tracking reference nor being mapped, and count it.
#include <gtest/gtest.h>

#include "rgbdtam/runtime/keyframe_pool.hpp"

namespace rgbdtam {
namespace {

TEST(KeyframePool, RecyclesTheOldestFreeKeyframeWhenFull) {
  KeyframeBuilder builder;
  builder.allocate(PinholeIntrinsics{50, 50, 31.5, 23.5, 64, 48}, TrackerOptions());
  KeyframePool pool;
  pool.allocate(3, builder, 16);
  Keyframe* a = pool.acquire(nullptr);
  Keyframe* b = pool.acquire(a);
  Keyframe* c = pool.acquire(b);
  EXPECT_EQ(pool.size(), 3);
  EXPECT_EQ(pool.recycled(), 0);
  EXPECT_TRUE(a != b && b != c && a != c);
  // Full: the oldest (a) goes, unless it is the reference.
  EXPECT_EQ(pool.acquire(c), a);
  EXPECT_EQ(pool.recycled(), 1);
  // Now b is the oldest; as the reference it stays, so c (the next oldest) goes.
  EXPECT_EQ(pool.acquire(b), c);
  // A keyframe being mapped is never recycled either.
  b->being_mapped.store(true);
  Keyframe* d = pool.acquire(c);
  EXPECT_NE(d, b);
  EXPECT_NE(d, c);
  EXPECT_EQ(pool.recycled(), 3);
}

}  // namespace
}  // namespace rgbdtam

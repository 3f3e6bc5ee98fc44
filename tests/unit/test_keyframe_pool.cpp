// The keyframe pool's policy when full: recycle the oldest keyframe that is neither the
// tracking reference nor being mapped, and count it.
#include <gtest/gtest.h>

#include "rgbdtam/runtime/keyframe_pool.hpp"

namespace rgbdtam {
namespace {

class KeyframePoolTest : public ::testing::Test {
 protected:
  void SetUp() override {
    builder.allocate(PinholeIntrinsics{50, 50, 31.5, 23.5, 64, 48}, TrackerOptions());
    pool.allocate(3, builder, 16);
  }
  KeyframeBuilder builder;
  KeyframePool pool;
};

TEST_F(KeyframePoolTest, RecyclesTheOldestFreeKeyframeWhenFull) {
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
  // A pinned keyframe (being mapped) is never recycled either.
  const KeyframeHandle pinned = pool.handle(b);
  pool.pin(pinned);
  Keyframe* d = pool.acquire(c);
  EXPECT_NE(d, b);
  EXPECT_NE(d, c);
  EXPECT_EQ(pool.recycled(), 3);
  EXPECT_EQ(pool.get(pinned), b);
  pool.unpin(pinned);
}

TEST_F(KeyframePoolTest, AHandleToARecycledKeyframeReadsAsGone) {
  Keyframe* a = pool.acquire(nullptr);
  const KeyframeHandle h = pool.handle(a);
  EXPECT_EQ(pool.get(h), a);
  Keyframe* b = pool.acquire(a);
  pool.acquire(b);
  EXPECT_EQ(pool.acquire(b), a) << "the oldest goes";
  EXPECT_EQ(pool.stale_lookups(), 0u);
  EXPECT_EQ(pool.get(h), nullptr) << "the eviction notice: the old handle is stale";
  EXPECT_EQ(pool.get(pool.handle(a)), a);
  EXPECT_EQ(pool.stale_lookups(), 1u) << "the refused lookup is counted, the good one not";
}

TEST_F(KeyframePoolTest, APublishedMapIsAdoptedOnceBetweenFrames) {
  Keyframe* a = pool.acquire(nullptr);
  EXPECT_FALSE(pool.adopt_map(a));
  const TrackPoints* before = &a->photometric(0);
  EXPECT_EQ(a->inactive_photometric(), &a->photometric_sets[1][0]);
  pool.publish_map(pool.handle(a));
  EXPECT_TRUE(pool.adopt_map(a));
  EXPECT_NE(&a->photometric(0), before) << "the mapper's set is now the active one";
  EXPECT_FALSE(pool.adopt_map(a)) << "adopted once";
}

}  // namespace
}  // namespace rgbdtam

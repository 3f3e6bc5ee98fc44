// The camera's clock carried over to the host's (core/device_clock): arrival jitter removed,
// the 32-bit counter's wrap followed, a camera reset started over.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "measures.hpp"
#include "rgbdtam/core/device_clock.hpp"

namespace rgbdtam {
namespace {

using testing::kMs;

TEST(DeviceClock, ArrivalJitterIsRemovedOnceOneFrameCameWithoutWaiting) {
  DeviceClock clock;
  clock.reset(1e6);  // microseconds, as a RealSense D4xx counts
  std::mt19937 rng(3);
  std::uniform_int_distribution<int64_t> jitter_ns(0, 6 * kMs);
  const int64_t transfer_ns = 9 * kMs, start_ns = 5000 * kMs;
  const uint32_t start_ticks = 123456;
  for (int i = 0; i < 200; ++i) {
    const int64_t capture_ns = start_ns + i * 33333333LL;
    // Frame 5 (and every 50th) comes without waiting; the others up to 6 ms late.
    const int64_t arrival_ns = capture_ns + transfer_ns + (i % 50 == 5 ? 0 : jitter_ns(rng));
    const uint32_t ticks = start_ticks + static_cast<uint32_t>((capture_ns - start_ns) / 1000);
    const int64_t stamp_ns = clock.to_host_ns(ticks, arrival_ns);
    EXPECT_LE(stamp_ns, arrival_ns) << "frame " << i;
    if (i >= 5) {
      EXPECT_NEAR(stamp_ns, capture_ns + transfer_ns, 1000) << "frame " << i;
    }
  }
}

TEST(DeviceClock, TheCountersWrapIsAStepForward) {
  DeviceClock clock;
  clock.reset(1e6);
  const uint32_t before_wrap = 0xFFFFFFFFu - 10000;  // 10 ms before the counter wraps
  EXPECT_EQ(clock.to_host_ns(before_wrap, 100 * kMs), 100 * kMs);
  // 33 ms later on the camera: past the wrap, and 1 ms less late than the first.
  EXPECT_EQ(clock.to_host_ns(before_wrap + 33000u, 133 * kMs), 133 * kMs);
  EXPECT_EQ(clock.to_host_ns(before_wrap + 66000u, 170 * kMs), 166 * kMs);
}

TEST(DeviceClock, AnotherStreamsEarlierFrameIsAStepBackAndARestartedCameraStartsOver) {
  DeviceClock clock;
  clock.reset(1e6);
  const uint32_t t = 500000000;  // 500 s since the camera started
  EXPECT_EQ(clock.to_host_ns(t, 1000 * kMs), 1000 * kMs);
  // Colour captured 5 ms before the depth frame just seen, and 2 ms less late.
  EXPECT_EQ(clock.to_host_ns(t - 5000, 993 * kMs), 993 * kMs);
  EXPECT_EQ(clock.to_host_ns(t + 33000, 1040 * kMs), 1031 * kMs);
  // The camera was reset: its clock starts near zero; the old differences no longer hold.
  EXPECT_EQ(clock.to_host_ns(500, 9000 * kMs), 9000 * kMs);
  EXPECT_EQ(clock.to_host_ns(33833, 9035 * kMs), 9033333 * 1000LL);
}

}  // namespace
}  // namespace rgbdtam

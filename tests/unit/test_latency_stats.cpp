#include "rgbdtam/port/latency_stats.hpp"

#include <gtest/gtest.h>

#include <memory>

namespace rgbdtam {
namespace {

// Percentiles are read at their 10 us bin's centre, which may lie above the largest sample.
TEST(LatencyStats, NoPercentileIsAboveTheLargestSample) {
  const auto stats = std::make_unique<LatencyStats>();  // 800 kB of bins
  stats->add(46'431'000);  // in the lower half of its bin, whose centre is 46.435 ms
  EXPECT_DOUBLE_EQ(stats->percentile_ms(0.5), stats->max_ms());
  EXPECT_DOUBLE_EQ(stats->percentile_ms(0.95), stats->max_ms());
  stats->add(1'003'000);
  EXPECT_NEAR(stats->percentile_ms(0.5), 1.005, 1e-9) << "below the max, the bin's centre";
  EXPECT_DOUBLE_EQ(stats->percentile_ms(0.95), stats->max_ms());
}

}  // namespace
}  // namespace rgbdtam

// Reading a structured-light sensor's depth units from the ladder its disparity steps make
// (issue 35, item 3: depth.factor 1000 on data made at 5000 sent 45 of 49 poses wrong).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "rgbdtam/core/depth_units.hpp"

namespace rgbdtam {
namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr double kFocalBaseline = 580.0 * 0.075;  // f b of a PrimeSense sensor, px m
constexpr double kQuantumPx = 0.125;              // its disparity's sub-pixel step
constexpr double kInverseDepthStep = kQuantumPx / kFocalBaseline;

enum class Depth { kSensor, kRendered };

// A slanted wall from 0.6 to 3.5 m, `moved_m` nearer, in raw units at `factor` per metre;
// quantised as the sensor's disparity is, or continuous as a renderer's.
std::vector<uint16_t> wall(double factor, Depth kind, double moved_m = 0.0) {
  std::vector<uint16_t> raw(static_cast<size_t>(kWidth) * kHeight);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      double z = 0.6 + 2.9 * (kHeight - 1 - y) / (kHeight - 1) + 0.2 * x / kWidth - moved_m;
      if (kind == Depth::kSensor) {
        z = kFocalBaseline / (std::round(kFocalBaseline / z / kQuantumPx) * kQuantumPx);
      }
      raw[static_cast<size_t>(y) * kWidth + x] = static_cast<uint16_t>(std::lround(z * factor));
    }
  }
  return raw;
}

// A floor 1 m below a 525 px camera, rendered: its inverse depth grows by the same step each
// row, a ladder of its own.
std::vector<uint16_t> rendered_floor(double moved_m) {
  std::vector<uint16_t> raw(static_cast<size_t>(kWidth) * kHeight, 0);
  for (int y = kHeight / 2 + 1; y < kHeight; ++y) {
    const double z = 525.0 / (y - kHeight / 2) - moved_m;
    for (int x = 0; x < kWidth; ++x) {
      raw[static_cast<size_t>(y) * kWidth + x] = static_cast<uint16_t>(std::lround(z * 5000.0));
    }
  }
  return raw;
}

// The reading of `second`, read after `first` (a frame is compared with the one before).
DepthUnitsReading read_after(const std::vector<uint16_t>& first,
                             const std::vector<uint16_t>& second, double factor) {
  DepthUnitsReader reader;
  const DepthUnitsReading alone =
      reader.read(first.data(), static_cast<int>(first.size()), factor, kInverseDepthStep);
  EXPECT_FALSE(alone.conclusive) << "a first frame has nothing to recur from";
  return reader.read(second.data(), static_cast<int>(second.size()), factor, kInverseDepthStep);
}

TEST(DepthUnits, ASensorsLadderReadsOneInItsUnitsAndTheMistakesFactorInOthers) {
  const std::vector<uint16_t> a = wall(5000.0, Depth::kSensor);
  const std::vector<uint16_t> b = wall(5000.0, Depth::kSensor, 0.01);
  const DepthUnitsReading right = read_after(a, b, 5000.0);
  ASSERT_TRUE(right.conclusive);
  EXPECT_NEAR(right.step_ratio, 1.0, 0.03);
  const DepthUnitsReading off = read_after(a, b, 1000.0);
  ASSERT_TRUE(off.conclusive);
  EXPECT_NEAR(off.step_ratio, 0.2, 0.2 * 0.03);
  EXPECT_NEAR(off.fitting_factor, 5000.0, 5000.0 * 0.03) << "what depth.factor should be";
  // Millimetres (OpenNI's units) read at 1000, and the mistake the other way: read as TUM's
  // fifths of a millimetre.
  const std::vector<uint16_t> mm_a = wall(1000.0, Depth::kSensor);
  const std::vector<uint16_t> mm_b = wall(1000.0, Depth::kSensor, 0.01);
  const DepthUnitsReading openni = read_after(mm_a, mm_b, 1000.0);
  ASSERT_TRUE(openni.conclusive);
  EXPECT_NEAR(openni.step_ratio, 1.0, 0.05);
  const DepthUnitsReading tum_config = read_after(mm_a, mm_b, 5000.0);
  ASSERT_TRUE(tum_config.conclusive);
  EXPECT_NEAR(tum_config.step_ratio, 5.0, 5.0 * 0.05);
}

TEST(DepthUnits, DepthWithoutAFixedLadderIsNotRead) {
  // A renderer's wall, its values everywhere between.
  EXPECT_FALSE(
      read_after(wall(5000.0, Depth::kRendered), wall(5000.0, Depth::kRendered, 0.01), 5000.0)
          .conclusive);
  // A renderer's floor: evenly spaced in inverse depth, but not at the same values once the
  // camera has moved 1 cm.
  EXPECT_FALSE(read_after(rendered_floor(0.0), rendered_floor(0.01), 5000.0).conclusive);
  // The same frame again (a camera standing still) tells nothing new.
  const std::vector<uint16_t> a = wall(5000.0, Depth::kSensor);
  EXPECT_FALSE(read_after(a, a, 1000.0).conclusive);
  const std::vector<uint16_t> none(static_cast<size_t>(kWidth) * kHeight, 0);
  EXPECT_FALSE(read_after(none, none, 5000.0).conclusive);
}

}  // namespace
}  // namespace rgbdtam

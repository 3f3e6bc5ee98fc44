#include "rgbdtam/core/depth_units.hpp"

#include <algorithm>
#include <cmath>

#include "rgbdtam/core/tracking_health.hpp"

namespace rgbdtam {
namespace {
// Spacings within this many raw units are the raw resolution, not a rung of the ladder.
constexpr int kRawResolution = 2;
constexpr int kMinSpacings = 50;
constexpr double kLadderSpread = 0.1;
constexpr double kMinOnLadder = 0.6;
constexpr double kMinRecurring = 0.75;
// The spacings' ratios to the model on a log scale: 1/16 to 16, 1 % a bin.
constexpr int kOctaves = 4;
constexpr int kBinsPerOctave = 64;
constexpr int kBins = 2 * kOctaves * kBinsPerOctave;

// Calls f(lower, upper) for each two neighbouring values the bitset holds, in increasing order.
template <typename F>
int each_spacing(const uint64_t* seen, int words, F f) {
  int spacings = 0, previous = 0;
  for (int w = 0; w < words; ++w) {
    for (uint64_t bits = seen[w]; bits != 0; bits &= bits - 1) {
      const int v = w * 64 + __builtin_ctzll(bits);
      if (previous != 0) {
        f(previous, v);
        ++spacings;
      }
      previous = v;
    }
  }
  return spacings;
}
}  // namespace

DepthUnitsReading DepthUnitsReader::read(const uint16_t* depth, int pixels, double depth_factor,
                                         double inverse_depth_step) {
  constexpr int kWords = kRawValues / 64;
  std::copy(seen_, seen_ + kWords, seen_before_);
  std::fill(seen_, seen_ + kWords, uint64_t{0});
  for (int i = 0; i < pixels; ++i) {
    const uint16_t v = depth[i];
    if (v != 0) seen_[v >> 6] |= uint64_t{1} << (v & 63);
  }
  const uint64_t fingerprint = sampled_fingerprint(depth, pixels);
  const bool another_frame = fingerprint != fingerprint_before_;
  fingerprint_before_ = fingerprint;
  int values = 0, recurring = 0;
  for (int w = 0; w < kWords; ++w) {
    values += __builtin_popcountll(seen_[w]);
    recurring += __builtin_popcountll(seen_[w] & seen_before_[w]);
  }
  int histogram[kBins] = {};
  int within_resolution = 0;
  const int spacings = each_spacing(seen_, kWords, [&](int lower, int upper) {
    if (upper - lower <= kRawResolution) ++within_resolution;
    // Inverse depths at the configured units: 1/z = factor / raw.
    const double step = depth_factor / lower - depth_factor / upper;
    const double octaves = std::log2(step / inverse_depth_step);
    const int bin = static_cast<int>(std::floor((octaves + kOctaves) * kBinsPerOctave));
    ++histogram[std::clamp(bin, 0, kBins - 1)];
  });
  DepthUnitsReading out;
  if (spacings < kMinSpacings || 2 * within_resolution >= spacings || !another_frame ||
      recurring < kMinRecurring * values) {
    return out;
  }
  int bin = 0;
  for (int below = 0; bin < kBins - 1 && below + histogram[bin] < (spacings + 1) / 2; ++bin) {
    below += histogram[bin];
  }
  // A ladder's rungs are evenly spaced: most values are followed by the next rung, within 10 %
  // or the raw unit they were rounded to (fr1_xyz and fr3_teddy: 70-76 % of them, 56 % in a
  // frame of fr1_xyz's end; millimetres, OpenNI's units, all of them). A renderer's depths, gaps
  // of any size between the values that happen to occur, are not read (the metre panels' first
  // frame: 53 %).
  const double ratio = std::exp2((bin + 0.5) / kBinsPerOctave - kOctaves);
  const double rung = ratio * inverse_depth_step;
  int on_ladder = 0;
  each_spacing(seen_, kWords, [&](int lower, int upper) {
    const double next_inverse = depth_factor / lower - rung;
    if (next_inverse <= 0.0) return;
    const double expected = depth_factor / next_inverse - lower;
    on_ladder += std::fabs(upper - lower - expected) <= std::max(kLadderSpread * expected, 1.0);
  });
  if (on_ladder < kMinOnLadder * spacings) return out;
  out.conclusive = true;
  out.step_ratio = ratio;
  out.fitting_factor = depth_factor / out.step_ratio;
  return out;
}

}  // namespace rgbdtam

#include "rgbdtam/core/kth_smallest.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "rgbdtam/core/assert.hpp"

namespace rgbdtam {
namespace {

constexpr int kBinBits = 11;
// Below this, counting 2 048 bins costs more than nth_element saves.
constexpr int kMinCounted = 1024;

// The float's bits as an unsigned key in the floats' order (negatives reversed below positives).
uint32_t ordered_key(float v) {
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return (bits & 0x80000000u) != 0 ? ~bits : bits | 0x80000000u;
}

uint32_t bin_of(float v) { return ordered_key(v) >> (32 - kBinBits); }

}  // namespace

float kth_smallest(float* values, int n, int k) {
  RGBDTAM_ASSERT(k >= 0 && k < n, "kth_smallest: rank outside the values");
  if (n < kMinCounted) {
    std::nth_element(values, values + k, values + n);
    return values[k];
  }
  uint32_t count[1u << kBinBits] = {};
  for (int i = 0; i < n; ++i) ++count[bin_of(values[i])];
  uint32_t bin = 0;
  int below = 0;
  while (below + static_cast<int>(count[bin]) <= k) below += static_cast<int>(count[bin++]);
  float* const in_bin_end =
      std::partition(values, values + n, [bin](float v) { return bin_of(v) == bin; });
  std::nth_element(values, values + (k - below), in_bin_end);
  return values[k - below];
}

}  // namespace rgbdtam

// The k-th smallest float, checked against a sorted copy on the kinds of values the tracker
// selects among: residuals around zero, their absolute deviations, repeats and signed zeros.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "rgbdtam/core/kth_smallest.hpp"
#include "rgbdtam/core/xorshift.hpp"

namespace rgbdtam {
namespace {

// About a hundred ranks spread over `values` (every one when fewer), the median and the last give
// the sorted copy's value there, and leave the same values.
void expect_ranks_as_sorted(const std::vector<float>& values, const char* what) {
  std::vector<float> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  const int n = static_cast<int>(values.size());
  std::vector<int> ranks;
  for (int k = 0; k < n; k += std::max(1, n / 97)) ranks.push_back(k);
  ranks.push_back(n / 2);
  ranks.push_back(n - 1);
  for (int k : ranks) {
    std::vector<float> work = values;
    EXPECT_EQ(kth_smallest(work.data(), n, k), sorted[k]) << what << ", n " << n << ", k " << k;
    std::sort(work.begin(), work.end());
    EXPECT_EQ(work, sorted) << what << ": the values were changed";
  }
}

float uniform(uint32_t* state) { return xorshift32(state) / 4294967296.0f; }

TEST(KthSmallest, RanksOfResidualsAndTheirDeviationsAreASortsAndNoValueIsLost) {
  uint32_t state = 12345;
  for (int n : {1, 2, 7, 1023, 1024, 1025, 5000, 20011}) {
    std::vector<float> residuals(n);
    // Heavy-tailed around zero, as photometric residuals are: a narrow core and wide outliers.
    for (float& r : residuals) {
      const float u = uniform(&state) - 0.5f;
      r = uniform(&state) < 0.9f ? 4 * u : 200 * u;
    }
    expect_ranks_as_sorted(residuals, "residuals");
    std::vector<float> deviations(n);
    for (int i = 0; i < n; ++i) deviations[i] = std::fabs(residuals[i] - 0.3f);
    expect_ranks_as_sorted(deviations, "absolute deviations");
  }
}

TEST(KthSmallest, RepeatsSignedZerosAndValuesInOneBin) {
  uint32_t state = 7;
  std::vector<float> repeats(3000);
  for (float& v : repeats) v = static_cast<float>(xorshift32(&state) % 5) - 2.f;
  expect_ranks_as_sorted(repeats, "five values repeated");
  std::vector<float> zeros(2000);
  for (size_t i = 0; i < zeros.size(); ++i) zeros[i] = i % 3 == 0 ? -0.f : i % 3 == 1 ? 0.f : 1.f;
  expect_ranks_as_sorted(zeros, "signed zeros and ones");
  // All in the same bin of the top bits: the selection among the bin is the whole work.
  std::vector<float> one_bin(4096);
  for (float& v : one_bin) v = 1.f + 0.2f * uniform(&state);
  expect_ranks_as_sorted(one_bin, "values in [1, 1.2)");
  std::vector<float> equal(1500, 3.25f);
  expect_ranks_as_sorted(equal, "all equal");
}

}  // namespace
}  // namespace rgbdtam

#pragma once
// Per-task time statistics without storing samples: a fixed histogram with 10 us bins.

#include <cstddef>
#include <cstdint>

namespace rgbdtam {

class LatencyStats {
 public:
  static constexpr int64_t kBinNs = 10'000;
  static constexpr int kBins = 200'000;  // 2 s; slower samples land in the last bin

  LatencyStats();
  void add(int64_t duration_ns);
  int64_t count() const { return count_; }
  double percentile_ms(double p) const;  // p in [0, 1]
  double max_ms() const { return static_cast<double>(max_ns_) * 1e-6; }
  double mean_ms() const { return count_ > 0 ? static_cast<double>(sum_ns_) * 1e-6 / count_ : 0.0; }
  // "median M, p95 P, max X" in ms with the given decimals, as summaries print it; returns out.
  const char* describe(int decimals, char* out, size_t size) const;

 private:
  uint32_t bins_[kBins];
  int64_t count_ = 0;
  int64_t max_ns_ = 0;
  int64_t sum_ns_ = 0;
};

}  // namespace rgbdtam

#include "rgbdtam/port/latency_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rgbdtam {

LatencyStats::LatencyStats() : bins_{} {}

void LatencyStats::add(int64_t ns) {
  ns = std::max<int64_t>(ns, 0);
  const int64_t bin = std::min<int64_t>(ns / kBinNs, kBins - 1);
  ++bins_[bin];
  ++count_;
  sum_ns_ += ns;
  max_ns_ = std::max(max_ns_, ns);
}

double LatencyStats::percentile_ms(double p) const {
  if (count_ == 0) return 0.0;
  // Nearest-rank percentile, reported at the bin centre, but never above the largest sample
  // (which may lie in the bin's lower half: the monitor showed a p95 above the max).
  const int64_t rank = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(p * count_)));
  int64_t seen = 0;
  for (int i = 0; i < kBins; ++i) {
    seen += bins_[i];
    if (seen >= rank) return std::min((static_cast<double>(i) + 0.5) * kBinNs * 1e-6, max_ms());
  }
  return max_ms();
}

const char* LatencyStats::describe(int decimals, char* out, size_t size) const {
  std::snprintf(out, size, "median %.*f, p95 %.*f, max %.*f", decimals, percentile_ms(0.5),
                decimals, percentile_ms(0.95), decimals, max_ms());
  return out;
}

}  // namespace rgbdtam

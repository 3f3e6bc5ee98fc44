#include "rgbdtam/hal/clock.hpp"

#include <ctime>

namespace rgbdtam {
int64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000LL + ts.tv_nsec;
}
}  // namespace rgbdtam

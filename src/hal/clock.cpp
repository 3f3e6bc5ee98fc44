#include "rgbdtam/hal/clock.hpp"

#include <errno.h>

#include <ctime>

namespace rgbdtam {
namespace {
int64_t clock_ns(clockid_t clock) {
  timespec ts;
  clock_gettime(clock, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000LL + ts.tv_nsec;
}
}  // namespace

int64_t monotonic_ns() { return clock_ns(CLOCK_MONOTONIC); }
int64_t unix_time_ns() { return clock_ns(CLOCK_REALTIME); }

void sleep_until_ns(int64_t deadline_ns) {
  const timespec t{static_cast<time_t>(deadline_ns / 1'000'000'000),
                   static_cast<long>(deadline_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
  }
}
}  // namespace rgbdtam

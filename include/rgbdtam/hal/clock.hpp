#pragma once
#include <cstdint>

namespace rgbdtam {
// CLOCK_MONOTONIC in nanoseconds.
int64_t monotonic_ns();
// CLOCK_REALTIME in nanoseconds since 1970 (for what a person reads, never for periods).
int64_t unix_time_ns();
// Sleeps until monotonic_ns() reaches deadline_ns (at once when it has).
void sleep_until_ns(int64_t deadline_ns);
}  // namespace rgbdtam

#pragma once
#include <cstdint>

namespace rgbdtam {
// CLOCK_MONOTONIC in nanoseconds.
int64_t monotonic_ns();
}  // namespace rgbdtam

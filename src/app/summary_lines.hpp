#pragma once
// Summary lines shared by replay and run.

#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {

// Places remembered and forgotten, edges, corrections, relocalisations and the loop module's
// times; nothing when loop closure is off.
void print_loop_summary(const SlamSystem& system);

// On stderr, when most frames had no usable depth or the depth stream repeated itself: tracking
// could not have been right, and the user should hear why.
void warn_about_depth(const TrackingCounters& c, const char* program);

}  // namespace rgbdtam

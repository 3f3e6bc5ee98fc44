#pragma once
// Summary lines shared by replay and run.

#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {

// Places remembered and forgotten, edges, corrections, relocalisations and the loop module's
// times; nothing when loop closure is off.
void print_loop_summary(const SlamSystem& system);

// On stderr, when most frames had no usable depth, the depth stream repeated itself or was read
// in other units than the sensor's: tracking could not have been right, and the user should hear
// why.
void warn_about_depth(const TrackingPipeline& tracking, const char* program);

}  // namespace rgbdtam

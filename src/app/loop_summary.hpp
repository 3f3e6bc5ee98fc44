#pragma once
// The summary's loop line, shared by replay and run.

#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {

// Places remembered and forgotten, edges, corrections, relocalisations and the loop module's
// times; nothing when loop closure is off.
void print_loop_summary(const SlamSystem& system);

}  // namespace rgbdtam

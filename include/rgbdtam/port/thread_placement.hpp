#pragma once
// Where a task's thread runs, from the board file, applied when the thread is started.

#include <thread>

#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

// cpu -1 = any CPU; priority 0 = the normal scheduler, 1-99 = SCHED_FIFO at that priority
// (needs CAP_SYS_NICE or an rtprio limit, else start-up fails with a clear error).
struct ThreadPlacement {
  int cpu = -1;
  int priority = 0;
};

// Names the thread (for top/gdb) and applies the placement.
Status place_thread(std::thread& t, const ThreadPlacement& p, const char* name);
// The same for the calling thread (the tracker runs on the thread that calls the runtime).
Status place_this_thread(const ThreadPlacement& p, const char* name);

}  // namespace rgbdtam

#pragma once
// The memory budget: a configuration that needs more than the machine may give is refused at
// init, naming the keys that size it, instead of aborting in the middle of allocating.
#include <cstddef>
#include <cstdint>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

struct MemoryBudget {
  uint64_t bytes = 0;
  char from[96] = "";  // where the figure comes from, for the messages
};

// board_mb > 0: that many MB (memory.budget_mb); 0: half of the machine's physical memory.
MemoryBudget memory_budget(int board_mb);
// vocabulary_words: of the loaded vocabulary, 0 without loop closure. sensor_bytes: what the
// sensor keeps beside the SLAM system (a registration thread's frames), counted with the camera's
// images. per_frame_bytes x frames: what the job keeps for every frame (a replay's results). Ok
// when the need fits; *needed_bytes is the need either way.
Status check_memory_budget(const Params& params, int vocabulary_words, size_t sensor_bytes,
                           size_t per_frame_bytes, int frames, const MemoryBudget& budget,
                           uint64_t* needed_bytes);

}  // namespace rgbdtam

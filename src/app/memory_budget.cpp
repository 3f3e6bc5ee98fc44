#include "memory_budget.hpp"

#include <cstdio>

#include "rgbdtam/hal/machine.hpp"
#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {

MemoryBudget memory_budget(int board_mb) {
  MemoryBudget b;
  if (board_mb > 0) {
    b.bytes = static_cast<uint64_t>(board_mb) << 20;
    std::snprintf(b.from, sizeof(b.from), "memory.budget_mb = %d", board_mb);
    return b;
  }
  const uint64_t physical = physical_memory_bytes();
  b.bytes = physical / 2;
  std::snprintf(b.from, sizeof(b.from), "half of this machine's %.0f MB",
                static_cast<double>(physical) / (1 << 20));
  return b;
}

Status check_memory_budget(const Params& params, int vocabulary_words, size_t sensor_bytes,
                           size_t per_frame_bytes, int frames, const MemoryBudget& budget,
                           uint64_t* needed_bytes) {
  const MemoryNeed need = memory_need(params, vocabulary_words);
  const uint64_t results = static_cast<uint64_t>(per_frame_bytes) * static_cast<uint64_t>(frames);
  *needed_bytes = need.total() + sensor_bytes + results;
  if (budget.bytes == 0 || *needed_bytes <= budget.bytes) return Status::ok();
  constexpr double kMb = 1 << 20;
  // One line of at most 255 characters (Status): the figures, then the key to lower first.
  return Status::error(
      StatusCode::kOutOfRange,
      "needs %.0f MB, over the %.0f MB budget (%s): map.keyframe_pool %d x %.1f MB, "
      "map.queue_frames+map.seeds %.0f MB, camera size %.0f MB, loop.places %.0f MB, %d frames "
      "%.0f MB; lower map.keyframe_pool",
      static_cast<double>(*needed_bytes) / kMb, static_cast<double>(budget.bytes) / kMb,
      budget.from, params.keyframe_pool_size, static_cast<double>(need.per_keyframe) / kMb,
      static_cast<double>(need.mapper) / kMb, static_cast<double>(need.images + sensor_bytes) / kMb,
      static_cast<double>(need.loop) / kMb, frames, static_cast<double>(results) / kMb);
}

}  // namespace rgbdtam

#pragma once
// Runs the replay job over a TUM folder with a shipped config and evaluates it.
#include <initializer_list>
#include <string>

#include "evaluate_command.hpp"
#include "replay_job.hpp"

namespace rgbdtam::testing {

struct ReplayOutcome {
  bool ran = false;
  Status status;  // why it did not run
  std::vector<StampedPose> estimates;
  int found_in_map_at_frame = -1;  // with a map file loaded
  TrackingCounters counters;
  EvaluationReport report;
  EvaluationReport final_report;  // every tracked frame on its keyframe's final pose
  LoopCounters loop;
  double tracking_median_ms = 0;
  // Heap allocations from the end of init to the end of the run, in a binary that counts them
  // (allocation_counting.hpp); -1 in one that does not.
  long allocations_after_init = -1;
};

// How a binary that counts allocations arms its counter, and disarms it (returning the count).
struct AllocationCounter {
  void (*arm)() = nullptr;
  long (*disarm)() = nullptr;
};
// Every replay_and_evaluate from then on counts its run's allocations with it.
void count_allocations_in_replays(AllocationCounter counter);

// Map files to start in and to save the final map to (either may be null).
struct MapFiles {
  const char* in = nullptr;
  const char* out = nullptr;
};

ReplayOutcome replay_and_evaluate(const std::string& sequence, const std::string& config,
                                  std::initializer_list<const char*> overrides = {},
                                  MapSink* map_sink = nullptr, MapFiles map_files = {});

// The committed clip as a D435 over V4L2 delivers it: its depth moved into a depth camera of
// its own (848x480, focal x0.85, 2.5 cm aside; rgbdtam-stress unregister) as dir/d435. Returns
// the shipped config with the keys that register it back, written as dir/d435.conf ("" when
// the clip could not be moved).
std::string clip_in_a_depth_camera_of_its_own(const std::string& dir);

// The robust-tracking promise on a replayed sequence: every frame is tracked or reported lost,
// never a wrong pose reported as tracked (false-valid), and at least min_coverage of the frames
// with ground truth get a pose. Prints the figures under label.
void expect_tracked_or_lost(const ReplayOutcome& out, const std::string& label,
                            double min_coverage);

}  // namespace rgbdtam::testing

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
};

// Map files to start in and to save the final map to (either may be null).
struct MapFiles {
  const char* in = nullptr;
  const char* out = nullptr;
};

ReplayOutcome replay_and_evaluate(const std::string& sequence, const std::string& config,
                                  std::initializer_list<const char*> overrides = {},
                                  MapSink* map_sink = nullptr, MapFiles map_files = {});

// The robust-tracking promise on a replayed sequence: every frame is tracked or reported lost,
// never a wrong pose reported as tracked (false-valid), and at least min_coverage of the frames
// with ground truth get a pose. Prints the figures under label.
void expect_tracked_or_lost(const ReplayOutcome& out, const std::string& label,
                            double min_coverage);

}  // namespace rgbdtam::testing

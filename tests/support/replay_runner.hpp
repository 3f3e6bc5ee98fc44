#pragma once
// Runs the replay job over a TUM folder with a shipped config and evaluates it.
#include <string>

#include "evaluate_command.hpp"
#include "replay_job.hpp"

namespace rgbdtam::testing {

struct ReplayOutcome {
  bool ran = false;
  TrackingCounters counters;
  EvaluationReport report;
  double tracking_median_ms = 0;
};

ReplayOutcome replay_and_evaluate(const std::string& sequence, const std::string& config,
                                  const char* override_assignment = nullptr,
                                  MapSink* map_sink = nullptr);

}  // namespace rgbdtam::testing

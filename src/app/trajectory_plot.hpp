#pragma once
// `rgbdtam eval ... --plot out.svg`: the estimate against the ground truth, as an SVG the project
// writes itself. Left, the top view: both trajectories (the estimate after the ATE's alignment)
// on the plane of the ground truth's two principal axes. Right, the position error over time.
// Lost stretches (frames with ground truth but no estimate) and false-valid poses are marked in
// both. Host-side: this allocates.

#include <string>
#include <vector>

#include "evaluate_command.hpp"
#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

struct PlotInput {
  const std::vector<StampedPose>* gt = nullptr;
  const std::vector<StampedPose>* est = nullptr;
  // The sequence's frames (rgb.txt): lost stretches are runs of them without an estimate. Null:
  // gaps in the estimate longer than three of its median intervals.
  const std::vector<double>* frame_stamps = nullptr;
  const EvaluationReport* report = nullptr;
  std::string title;
};

// A time interval [begin_s, end_s] with ground truth but no estimate.
struct LostStretch {
  double begin_s, end_s;
};
std::vector<LostStretch> lost_stretches(const PlotInput& in);

std::string trajectory_svg(const PlotInput& in);
// Written as <path>.partial and renamed when complete.
Status write_trajectory_svg(const char* path, const PlotInput& in);

}  // namespace rgbdtam

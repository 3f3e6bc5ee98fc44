#pragma once
#include <vector>

#include "rgbdtam/core/evaluation.hpp"

namespace rgbdtam {

struct EvaluationReport {
  bool ate_ok = false, rpe_ok = false;
  AteResult ate;
  RpeResult rpe;
  Coverage coverage;
  bool has_coverage = false;
  FalseValidResult false_valid;
  NeesResult nees;  // only where the estimates come with covariances (replay)
};

EvaluationReport evaluate_all(const std::vector<StampedPose>& gt,
                              const std::vector<StampedPose>& est,
                              const std::vector<double>* frame_stamps);
void print_report(const EvaluationReport& r, bool json, const char* label);
int evaluate_command(int argc, char** argv);

}  // namespace rgbdtam

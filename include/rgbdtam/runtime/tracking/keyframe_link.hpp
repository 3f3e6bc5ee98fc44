#pragma once
// What ties a new keyframe into the map's graph.

#include <cstdint>

#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/port/messages.hpp"

namespace rgbdtam {

// The keyframe or place a new keyframe was measured against, how, the measurement, and its
// information (graph convention).
struct KeyframeLink {
  uint32_t reference_id = 0;
  EdgeKind kind = EdgeKind::kRestart;
  SE3 T_reference_keyframe;
  Matrix6d information = Matrix6d::Zero();
};

}  // namespace rgbdtam

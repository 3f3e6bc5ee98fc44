#pragma once
// What ties a new keyframe into the map's graph.

#include <cstdint>

#include "rgbdtam/core/assert.hpp"
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

// The local window's measurements of a new keyframe (kind kCovisible), most visible first.
struct WindowLinks {
  KeyframeLink link[kMaxWindowEdges];
  int count = 0;
  void add(const KeyframeLink& l) {
    RGBDTAM_ASSERT(count < kMaxWindowEdges, "more window measurements than kMaxWindowEdges");
    link[count++] = l;
  }
};

}  // namespace rgbdtam

#pragma once
// Where other sensors' knowledge of the camera's motion enters tracking: today the autopilot's
// rotation between two frames. A prior gives the first guess, is gated by the image's own pose
// (never forced: a prior that disagrees is dropped for the frame and counted), and gives one more
// start to the wider basin. A new prior adds its setter and these three answers here, and
// nothing elsewhere. Thread: the tracker's.

#include <cstdint>

#include "rgbdtam/core/attitude.hpp"
#include "rgbdtam/runtime/tracking/motion_state.hpp"

namespace rgbdtam {

struct PriorCounters {
  uint32_t prior_used = 0;      // frames whose first guess turned by a prior stood
  uint32_t prior_rejected = 0;  // ... did not (the image disagreed): tracked without it
};

class MotionPriors {
 public:
  // For the next frame only: the camera's turn since the last tracked frame, as another sensor
  // saw it (from MotionState::last_tracked_ns() to the frame's stamp; otherwise ignored).
  void set_rotation(const RotationPrior& prior) { rotation_ = prior; }

  // The first guess where a prior applies to the frame at t_ns, tracking being continuous:
  // the prediction turned by it.
  bool first_guess(const MotionState& motion, int64_t t_ns, const SE3& predicted, SE3* guess) const;
  // Whether the pose the image gave from first_guess stands: healthy, and agreeing with the
  // prior (counted). A prior that does not stand is dropped for this frame.
  bool stands(const MotionState& motion, const SE3& T_w_c, bool healthy);
  // A start for the wider basin (a turn faster than the basin), where a prior still applies.
  bool basin_guess(const MotionState& motion, int64_t t_ns, const SE3& predicted, SE3* guess) const;

  const PriorCounters& counters() const { return counters_; }

 private:
  bool rotation_applies(const MotionState& motion, int64_t t_ns) const;
  SE3 turned(const MotionState& motion, const SE3& predicted) const;

  RotationPrior rotation_;  // this frame's, if any
  PriorCounters counters_;
};

}  // namespace rgbdtam

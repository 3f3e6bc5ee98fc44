#pragma once
// Loop corrections in the poses sent. Tracking moves to the corrected map at once; the poses
// sent follow it no faster than the blend rate, so a small correction reaches the consumer with
// no jump and no reset. A reset costs an ArduPilot consumer a second of vision data (its
// AP_VisualOdom ignores the poses for 1 s after the counter changes); a jump sent valid is
// motion to anyone who differences poses. A correction the poses sent cannot take up within
// the longest blend is sent at once, with the reset counter (MotionState::correct).
// Thread: the tracker's.

#include <cstdint>

#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

struct BlendLimits {
  double rate_m_per_s = 0.0;  // 0: every correction is sent at once
  double rate_rad_per_s = 0.0;
  double max_s = 0.0;  // the longest a blend may take: what the rates take up in it, at the camera
};

class CorrectionBlend {
 public:
  void init(const BlendLimits& limits) { limits_ = limits; }

  // The camera's world moved by delta (T_w'_w), the camera last at T_w_c before it. True when the
  // poses sent take it up gradually; else the blend ends, and *sent_jump is how far the next
  // pose sent jumps (what was still being blended in included).
  bool absorb(const SE3& delta, const SE3& T_w_c, SE3* sent_jump);
  // The pose to send for tracking's T_w_c at t_ns: moved towards it by the rate since the last
  // pose sent. A new reset counter ends the blend (the consumers start again anyway).
  SE3 sent(const SE3& T_w_c, int64_t t_ns, uint32_t reset_counter);

  bool blending() const { return blending_; }
  // The step the last pose sent took towards tracking's, beyond the camera's own motion.
  double last_step_m() const { return last_step_m_; }
  double last_step_rad() const { return last_step_rad_; }

 private:
  BlendLimits limits_;
  SE3 T_sent_w_;  // the sent world from tracking's; identity when not blending
  bool blending_ = false;
  int64_t last_ns_ = -1;
  uint32_t reset_counter_ = 0;
  double last_step_m_ = 0.0;
  double last_step_rad_ = 0.0;
};

}  // namespace rgbdtam

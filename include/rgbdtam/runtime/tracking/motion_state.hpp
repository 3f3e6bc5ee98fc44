#pragma once
// The camera's motion as tracking knows it: the last valid pose, its time and the twist before
// it (the prediction), whether the frame before this one was valid, since when tracking has
// been lost, the reset counter that tells consumers when two poses sent stop being comparable
// (a restart, a relocalisation, a loop correction sent at once), and the map epoch that tells
// the mapper and the keyframe builder when the map moved (those, and a correction blended in).
// Every write of these is here.
// Thread: the tracker's.

#include <cstdint>

#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/core/tracking_health.hpp"
#include "rgbdtam/port/messages.hpp"

namespace rgbdtam {

// What the corrections since the last frame did to it: the flags (PoseFlags) and how far they
// moved the camera, summed.
struct CorrectionJump {
  uint32_t flags = 0;
  double translation_m = 0.0;
  double rotation_rad = 0.0;
};

struct MotionCounters {
  uint32_t resets = 0;               // restarts after a loss
  uint32_t loop_corrections = 0;     // loop closures that moved the camera's world
  uint32_t blended_corrections = 0;  // ... of which the poses sent took up gradually
};

class MotionState {
 public:
  // motion_model: predict with constant velocity (else the last pose); reset_after_lost_ns:
  // also how long poses stay withheld after a large correction.
  void init(bool motion_model, int64_t reset_after_lost_ns);

  bool has_last() const { return has_last_; }
  const SE3& T_w_last() const { return T_w_last_; }
  int64_t last_ns() const { return last_ns_; }
  int64_t last_tracked_ns() const { return has_last_ ? last_ns_ : -1; }
  bool previous_valid() const { return previous_valid_; }
  // The velocity was measured between two valid poses close in time: the prediction holds up to
  // the camera's acceleration.
  bool has_velocity() const { return has_velocity_; }
  uint32_t reset_counter() const { return reset_counter_; }
  // The camera's world: a restart or relocalisation begins an epoch, any loop correction
  // (blended or not) moves it by a known motion.
  const MapFrame& map_frame() const { return map_frame_; }
  double seconds_since_last(int64_t t_ns) const {
    return static_cast<double>(t_ns - last_ns_) * 1e-9;
  }
  // The last pose moved on at the current velocity for dt_s; predict() to the frame's time.
  SE3 extrapolate(double dt_s) const { return T_w_last_ * SE3::exp(velocity_ * dt_s); }
  // The camera's motion over dt_s at the current velocity (none without one).
  SE3 motion_over(double dt_s) const { return has_velocity_ ? SE3::exp(velocity_ * dt_s) : SE3(); }
  // The same as a twist: the motion over one rolling shutter's readout.
  Vector6d twist_over(double dt_s) const {
    return has_velocity_ ? Vector6d(velocity_ * dt_s) : Vector6d::Zero();
  }
  SE3 predict(int64_t t_ns) const { return extrapolate(seconds_since_last(t_ns)); }
  // A frame at t_ns tracked on from the last valid pose gives a velocity (has_velocity() after
  // track(), continuous): the two are close enough in time for the camera's motion between them.
  bool continuous_to(int64_t t_ns) const;
  // The motion from the last valid pose to T_w_c at t_ns, for the health checks' physical
  // limits (dt 0 without an earlier pose).
  HealthContext context(const SE3& T_w_c, int64_t t_ns, double typical_sigma) const;

  // The first pose of a world, or a pose found without tracking (relocalised onto a new
  // keyframe): no velocity carries into it.
  void begin(const SE3& T_w_c, int64_t t_ns);
  // The frame at t_ns was tracked at T_w_c. continuous: from the last valid pose (else, as after
  // a relocalisation, no velocity is estimated across).
  void track(const SE3& T_w_c, int64_t t_ns, bool continuous);
  // The same frame's pose, measured again against another keyframe (map reuse): the velocity
  // stays the one its first estimate gave.
  void remeasure(const SE3& T_w_c) { T_w_last_ = T_w_c; }
  // A lost frame: how long tracking has been lost, counted from the first lost frame.
  int64_t lost_for_ns(int64_t t_ns);
  // Tracking restarts at the last valid pose, as if it had been measured now.
  void restart(int64_t t_ns);
  // The estimate jumped (relocalisation) from the last valid pose at last_valid_ns (-1: none):
  // poses before and after are not comparable, and none is reported valid while a consumer
  // could difference it with that one.
  void jumped(int64_t last_valid_ns);
  // A loop correction moved the camera's world by delta (T_w'_w), and the poses sent jump with it
  // by sent_jump: the reset counter steps, and a jump larger than the limits withholds poses
  // while consumers could difference them across it.
  void correct(const SE3& delta, const SE3& sent_jump, double max_reported_jump_m,
               double max_reported_jump_rad);
  // A loop correction the poses sent take up gradually (CorrectionBlend): no jump, no reset.
  void correct_blended(const SE3& delta);
  // The corrections since the last frame, for the next output; cleared.
  CorrectionJump take_correction();
  // A tracked pose at t_ns is not reported valid: too soon after a large correction or a jump.
  bool withheld(int64_t t_ns) const { return t_ns <= withhold_until_ns_; }
  // Whether this frame was valid: the next one's guess is certain or not.
  void end_frame(bool valid) { previous_valid_ = valid; }

  const MotionCounters& counters() const { return counters_; }

 private:
  void new_epoch();
  void moved(const SE3& delta);  // by a loop correction, T_w'_w

  bool motion_model_ = true;
  int64_t reset_after_lost_ns_ = 0;
  SE3 T_w_last_;
  int64_t last_ns_ = 0;
  Vector6d velocity_ = Vector6d::Zero();  // twist (v, omega) per second before the last pose
  bool has_velocity_ = false;
  bool has_last_ = false;
  bool previous_valid_ = false;
  int64_t lost_since_ns_ = -1;  // the first lost frame of the current loss; -1 when tracking
  uint32_t reset_counter_ = 0;
  MapFrame map_frame_;
  CorrectionJump correction_;
  int64_t withhold_until_ns_ = 0;
  MotionCounters counters_;
};

}  // namespace rgbdtam

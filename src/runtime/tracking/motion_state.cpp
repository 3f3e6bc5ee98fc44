#include "rgbdtam/runtime/tracking/motion_state.hpp"

#include <algorithm>

#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {
namespace {
constexpr int64_t kMaxVelocityGapNs = static_cast<int64_t>(kMaxVelocityGapS * 1e9);
}  // namespace

void MotionState::init(bool motion_model, int64_t reset_after_lost_ns) {
  motion_model_ = motion_model;
  reset_after_lost_ns_ = reset_after_lost_ns;
}

HealthContext MotionState::context(const SE3& T_w_c, int64_t t_ns, double typical_sigma) const {
  HealthContext context;
  context.typical_sigma = typical_sigma;
  if (has_last_ && t_ns > last_ns_) {
    context.T_last_current = T_w_last_.inverse() * T_w_c;
    context.dt_s = seconds_since_last(t_ns);
    context.predicted = has_velocity_;
    if (has_velocity_) {
      context.from_prediction_m = (predict(t_ns).translation() - T_w_c.translation()).norm();
    }
  }
  return context;
}

void MotionState::begin(const SE3& T_w_c, int64_t t_ns) {
  T_w_last_ = T_w_c;
  last_ns_ = t_ns;
  has_last_ = true;
  velocity_.setZero();
  has_velocity_ = false;
  lost_since_ns_ = -1;  // a later loss restarts from this pose, not sooner
}

bool MotionState::continuous_to(int64_t t_ns) const {
  const int64_t gap = t_ns - last_ns_;
  return motion_model_ && has_last_ && gap > 0 && gap <= kMaxVelocityGapNs;
}

void MotionState::track(const SE3& T_w_c, int64_t t_ns, bool continuous) {
  velocity_.setZero();
  has_velocity_ = continuous && continuous_to(t_ns);
  if (has_velocity_) {
    velocity_ = (T_w_last_.inverse() * T_w_c).log() / seconds_since_last(t_ns);
  }
  T_w_last_ = T_w_c;
  last_ns_ = t_ns;
  has_last_ = true;
  lost_since_ns_ = -1;
}

int64_t MotionState::lost_for_ns(int64_t t_ns) {
  // Counted from the first lost frame: after an outage of the sensor the frames that follow
  // are relocalisation's chances, not lost time already spent.
  if (lost_since_ns_ < 0) lost_since_ns_ = t_ns;
  return t_ns - lost_since_ns_;
}

void MotionState::new_epoch() {
  ++map_frame_.epoch;
  map_frame_.corrections = 0;
  map_frame_.T_now_epoch = SE3();
}

void MotionState::moved(const SE3& delta) {
  ++map_frame_.corrections;
  map_frame_.T_now_epoch = delta * map_frame_.T_now_epoch;
}

void MotionState::restart(int64_t t_ns) {
  new_epoch();
  lost_since_ns_ = -1;
  last_ns_ = t_ns;
  velocity_.setZero();
  has_velocity_ = false;
  ++reset_counter_;
  ++counters_.resets;
}

void MotionState::correct(const SE3& delta, const SE3& sent_jump, double max_reported_jump_m,
                          double max_reported_jump_rad) {
  T_w_last_ = delta * T_w_last_;
  // Poses either side of a large jump are not comparable: as after a restart, none is
  // reported over the window in which a consumer differences poses.
  const double jump_m = sent_jump.translation().norm();
  const double jump_rad = so3_log(sent_jump.quaternion()).norm();
  if (jump_m > max_reported_jump_m || jump_rad > max_reported_jump_rad) {
    withhold_until_ns_ = last_ns_ + reset_after_lost_ns_;
  }
  ++reset_counter_;
  moved(delta);
  ++counters_.loop_corrections;
  correction_.flags |= kLoopCorrected | kReset;
  correction_.translation_m += jump_m;
  correction_.rotation_rad += jump_rad;
}

void MotionState::correct_blended(const SE3& delta) {
  moved(delta);
  T_w_last_ = delta * T_w_last_;
  ++counters_.loop_corrections;
  ++counters_.blended_corrections;
  correction_.flags |= kLoopCorrected;
}

void MotionState::jumped(int64_t last_valid_ns) {
  // Nothing measured the motion across the jump: no pose within the consumers' differencing
  // window of the last one before it, as after a restart.
  if (last_valid_ns >= 0) {
    withhold_until_ns_ = std::max(withhold_until_ns_, last_valid_ns + reset_after_lost_ns_);
  }
  ++reset_counter_;
  new_epoch();
}

CorrectionJump MotionState::take_correction() {
  const CorrectionJump taken = correction_;
  correction_ = CorrectionJump();
  return taken;
}

}  // namespace rgbdtam

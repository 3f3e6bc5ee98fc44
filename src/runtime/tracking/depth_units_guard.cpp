#include "rgbdtam/runtime/tracking/depth_units_guard.hpp"

namespace rgbdtam {

void DepthUnitsGuard::init(const SensorModel& sensor) {
  depth_factor_ = sensor.depth_factor;
  inverse_depth_step_ = sensor.disparity_quantum_px / (sensor.depth_focal_px * sensor.baseline_m);
  state_ = State::kReading;
  tried_ = right_in_a_row_ = off_in_a_row_ = 0;
  off_reading_ = DepthUnitsReading();
}

bool DepthUnitsGuard::off(const uint16_t* depth, int pixels) {
  if (state_ != State::kReading) return state_ == State::kOff;
  const DepthUnitsReading r = reader_.read(depth, pixels, depth_factor_, inverse_depth_step_);
  ++tried_;
  const bool off = r.conclusive && (r.step_ratio > kTolerance || r.step_ratio < 1.0 / kTolerance);
  if (off) off_reading_ = r;
  // In a row among the frames read: one without a ladder says nothing either way.
  if (r.conclusive) {
    right_in_a_row_ = off ? 0 : right_in_a_row_ + 1;
    off_in_a_row_ = off ? off_in_a_row_ + 1 : 0;
  }
  if (off_in_a_row_ == kFramesToLatch) {
    state_ = State::kOff;
  } else if (right_in_a_row_ == kFramesToLatch) {
    state_ = State::kRight;
  } else if (tried_ == kFramesToTry) {
    state_ = State::kNotChecked;
  }
  return off;
}

}  // namespace rgbdtam

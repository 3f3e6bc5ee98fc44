#pragma once
// The depth's units, read from the first frames (core/depth_units.hpp). A frame whose depth
// reads more than kTolerance off the sensor model is refused; kFramesToLatch such frames in a row
// (of those read: a frame without a ladder says nothing) settle it for the run, as do
// kFramesToLatch within it the other way. A sensor whose depth has no ladder is not checked
// after kFramesToTry frames.
//
// A units mistake is a factor of 2, 5, 10 or 1000. A quarter: the depth's scale is the
// translation's, and a quarter of a walking pace over the false-valid window is already 6 cm of
// its 10; the readings themselves are within 2 % (fr1_xyz 1.003, fr3_teddy 1.019), and a
// datasheet's baseline and focal length within a few per cent.
//
// Thread: the tracker's.

#include "rgbdtam/core/depth_units.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

class DepthUnitsGuard {
 public:
  static constexpr double kTolerance = 1.25;
  static constexpr int kFramesToLatch = 3;
  static constexpr int kFramesToTry = 30;

  void init(const SensorModel& sensor);
  // Whether this frame's depth is in the wrong units.
  bool off(const uint16_t* depth, int pixels);
  bool latched_off() const { return state_ == State::kOff; }
  // The last conclusive reading beyond the tolerance (conclusive false: none).
  const DepthUnitsReading& off_reading() const { return off_reading_; }

 private:
  enum class State { kReading, kRight, kOff, kNotChecked };
  DepthUnitsReader reader_;
  double depth_factor_ = 0.0, inverse_depth_step_ = 0.0;
  State state_ = State::kReading;
  int tried_ = 0, right_in_a_row_ = 0, off_in_a_row_ = 0;
  DepthUnitsReading off_reading_;
};

}  // namespace rgbdtam

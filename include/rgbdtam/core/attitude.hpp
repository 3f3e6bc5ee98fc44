#pragma once
// The autopilot's attitude, used two ways: the rotation between two frames as a prior for the
// tracker's first guess, and gravity to level the frame the robot's pose is reported in.
//
// Frames: n is the autopilot's level frame (north-east-down, or any frame whose z is down), b
// its body (front-right-down), c our camera, w our world (the first camera of the map), l the
// level frame ODOMETRY is sent in (z down, x the forward direction of the body at w's origin).

#include <cstdint>

#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

struct AttitudeSample {
  int64_t t_ns = 0;  // in the sensor's clock (the autopilot's time moved by the TIMESYNC offset)
  Eigen::Quaterniond q_n_b = Eigen::Quaterniond::Identity();
  Vector3d rate_b_rad_s = Vector3d::Zero();  // body rates, as reported
  double timing_sigma_s = 0;  // how well t_ns is known (half the TIMESYNC round trip)
};

// Aerospace Euler angles (yaw, then pitch, then roll, as MAVLink's ATTITUDE sends them) as the
// rotation from the level frame to the body.
Eigen::Quaterniond quaternion_from_yaw_pitch_roll(double yaw_rad, double pitch_rad,
                                                  double roll_rad);

// The latest attitudes, in a fixed ring: the attitude at any time they cover, interpolated.
class AttitudeHistory {
 public:
  static constexpr int kCapacity = 128;  // 1.28 s at 100 Hz, 2.56 s at 50 Hz
  // Beyond the newest sample the attitude is carried on by its rates only this far: a frame
  // may be tracked before the autopilot's sample of its instant has crossed the link.
  static constexpr int64_t kMaxExtrapolationNs = 50'000'000;

  // False (and nothing kept) for a sample not newer than the last or not finite.
  bool add(const AttitudeSample& s);
  // The attitude at t_ns; false when the samples do not cover it.
  bool at(int64_t t_ns, Eigen::Quaterniond* q_n_b) const;
  // The larger body rate of the samples around t_ns (rad/s), for the timing error's share.
  double rate_near(int64_t t_ns) const;
  int size() const { return size_; }
  void clear() { size_ = 0; }

 private:
  const AttitudeSample& nth(int i) const { return ring_[(first_ + i) % kCapacity]; }
  int upper_bound(int64_t t_ns) const;  // first sample later than t_ns, or size_

  AttitudeSample ring_[kCapacity];
  int first_ = 0, size_ = 0;
};

// The camera's rotation between two instants (from the earlier camera to the later one, R_c0_c1)
// as the autopilot saw it, with its standard deviation (rad).
struct RotationPrior {
  bool valid = false;
  int64_t from_ns = 0, to_ns = 0;
  Eigen::Quaterniond q_c0_c1 = Eigen::Quaterniond::Identity();
  double sigma_rad = 0;
};

// sigma: the attitude's own noise over the interval, and its rate times the timing uncertainty
// (the TIMESYNC offset's), added in quadrature.
RotationPrior rotation_prior(const AttitudeHistory& history, const SE3& T_b_c, int64_t from_ns,
                             int64_t to_ns, double attitude_sigma_rad, double timing_sigma_s);

// Gravity's direction (down, unit) in the world, from the body's attitude at the instant the
// camera was at T_w_c.
Vector3d down_in_world(const Eigen::Quaterniond& q_n_b, const SE3& T_b_c, const SE3& T_w_c);

// The level frame from the world: its z along down_w, its x the forward direction of the body
// at the world's origin, on the horizontal (that body's front is not vertical).
Eigen::Quaterniond level_from_world(const Vector3d& down_w, const SE3& T_b_c);

// Gravity seen over several frames: it stands once the last kFrames estimates agree within
// kAgreeRad of their mean, which a timing error on a turning body does not give.
class GravityEstimate {
 public:
  static constexpr int kFrames = 10;
  static constexpr double kAgreeRad = 1.0 * 3.14159265358979 / 180.0;
  void add(const Vector3d& down_w);
  void clear() { size_ = 0; }
  // The mean of the last kFrames estimates when they agree.
  bool agreed(Vector3d* down_w) const;

 private:
  Vector3d last_[kFrames];
  int next_ = 0, size_ = 0;
};

// The angle between two rotations (rad).
double angle_between(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

}  // namespace rgbdtam

#pragma once
// What the autopilot's attitude gives the tracker's thread: the camera's turn since the last
// tracked frame (a prior the tracker checks against the image) and the level frame the pose is
// sent in. Samples come from the link's thread, already in the sensor's clock; without them
// nothing changes.

#include <cstdint>

#include "rgbdtam/core/attitude.hpp"
#include "rgbdtam/port/messages.hpp"

namespace rgbdtam {

struct AttitudeAidCounters {
  uint32_t samples = 0;     // attitudes kept
  uint32_t refused = 0;     // out of order or not a rotation
  uint32_t priors = 0;      // frames given the autopilot's turn
  uint32_t levellings = 0;  // level frames found (one per segment of the trajectory)
};

class AttitudeAid {
 public:
  // attitude_sigma_rad: the autopilot's attitude noise over one frame's interval.
  void init(const SE3& T_b_c, double attitude_sigma_rad);
  void add(const AttitudeSample& s);
  // The camera's turn from from_ns to to_ns, invalid where the samples do not cover both.
  RotationPrior prior(int64_t from_ns, int64_t to_ns);
  // After a pose: valid poses with an attitude at their instant estimate gravity in the world;
  // once the last ten agree (GravityEstimate), their mean fixes the level frame of that segment
  // (reset_counter).
  void on_pose(const PoseEstimate& pose);
  bool levelled() const { return levelled_; }
  const Eigen::Quaterniond& q_l_w() const { return q_l_w_; }
  const AttitudeAidCounters& counters() const { return counters_; }

 private:
  SE3 T_b_c_;
  double attitude_sigma_rad_ = 0;
  double timing_sigma_s_ = 0;  // the newest sample's
  AttitudeHistory history_;
  GravityEstimate gravity_;
  uint32_t gravity_reset_ = 0;  // the segment gravity_ is of
  bool levelled_ = false;
  uint32_t levelled_reset_ = 0;
  Eigen::Quaterniond q_l_w_ = Eigen::Quaterniond::Identity();
  AttitudeAidCounters counters_;
};

}  // namespace rgbdtam

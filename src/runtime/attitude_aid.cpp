#include "rgbdtam/runtime/attitude_aid.hpp"

namespace rgbdtam {

void AttitudeAid::init(const SE3& T_b_c, double attitude_sigma_rad) {
  T_b_c_ = T_b_c;
  attitude_sigma_rad_ = attitude_sigma_rad;
}

void AttitudeAid::add(const AttitudeSample& s) {
  if (!history_.add(s)) {
    ++counters_.refused;
    return;
  }
  ++counters_.samples;
  timing_sigma_s_ = s.timing_sigma_s;
}

RotationPrior AttitudeAid::prior(int64_t from_ns, int64_t to_ns) {
  const RotationPrior p =
      rotation_prior(history_, T_b_c_, from_ns, to_ns, attitude_sigma_rad_, timing_sigma_s_);
  counters_.priors += p.valid ? 1 : 0;
  return p;
}

void AttitudeAid::on_pose(const PoseEstimate& pose) {
  if ((pose.flags & kPoseValid) == 0) return;
  if (levelled_ && pose.reset_counter == levelled_reset_) return;
  if (pose.reset_counter != gravity_reset_) {  // another world: estimates start again
    gravity_.clear();
    gravity_reset_ = pose.reset_counter;
  }
  Eigen::Quaterniond q_n_b;
  if (!history_.at(pose.timestamp_ns, &q_n_b)) return;
  gravity_.add(down_in_world(q_n_b, T_b_c_, pose.T_w_c));
  Vector3d down_w;
  if (!gravity_.agreed(&down_w)) return;
  q_l_w_ = level_from_world(down_w, T_b_c_);
  levelled_ = true;
  levelled_reset_ = pose.reset_counter;
  ++counters_.levellings;
}

}  // namespace rgbdtam

#include "rgbdtam/runtime/tracking/motion_priors.hpp"

namespace rgbdtam {
namespace {
// A prior and the image agree when they differ by less than this many of the prior's standard
// deviations (the image's own rotation error, some 0.05 degrees, is small beside it).
constexpr double kPriorGateSigmas = 3.0;
}  // namespace

bool MotionPriors::rotation_applies(const MotionState& motion, int64_t t_ns) const {
  return rotation_.valid && motion.has_last() && rotation_.from_ns == motion.last_ns() &&
         rotation_.to_ns == t_ns;
}

SE3 MotionPriors::turned(const MotionState& motion, const SE3& predicted) const {
  return SE3(motion.T_w_last().quaternion() * rotation_.q_c0_c1, predicted.translation());
}

bool MotionPriors::first_guess(const MotionState& motion, int64_t t_ns, const SE3& predicted,
                               SE3* guess) const {
  if (!rotation_applies(motion, t_ns) || !motion.previous_valid()) return false;
  *guess = turned(motion, predicted);
  return true;
}

bool MotionPriors::stands(const MotionState& motion, const SE3& T_w_c, bool healthy) {
  const double disagreement = angle_between(
      rotation_.q_c0_c1, motion.T_w_last().quaternion().conjugate() * T_w_c.quaternion());
  if (healthy && disagreement <= kPriorGateSigmas * rotation_.sigma_rad) {
    ++counters_.prior_used;
    return true;
  }
  // Never forced: the frame is tracked as without it, and no later guess uses it.
  ++counters_.prior_rejected;
  rotation_.valid = false;
  return false;
}

bool MotionPriors::basin_guess(const MotionState& motion, int64_t t_ns, const SE3& predicted,
                               SE3* guess) const {
  if (!rotation_applies(motion, t_ns)) return false;
  *guess = turned(motion, predicted);
  return true;
}

}  // namespace rgbdtam

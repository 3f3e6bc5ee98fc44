#include "rgbdtam/runtime/tracking/correction_blend.hpp"

#include <algorithm>
#include <limits>

namespace rgbdtam {

bool CorrectionBlend::absorb(const SE3& delta, const SE3& T_w_c, SE3* sent_jump) {
  const SE3 last_sent = T_sent_w_ * T_w_c;
  const SE3 jump = last_sent.inverse() * (delta * T_w_c);
  if (limits_.rate_m_per_s > 0.0 && limits_.rate_rad_per_s > 0.0 &&
      within(jump, limits_.rate_m_per_s * limits_.max_s, limits_.rate_rad_per_s * limits_.max_s)) {
    T_sent_w_ = T_sent_w_ * delta.inverse();  // the pose sent does not move
    blending_ = true;
    return true;
  }
  *sent_jump = jump;
  T_sent_w_ = SE3();
  blending_ = false;
  return false;
}

SE3 CorrectionBlend::sent(const SE3& T_w_c, int64_t t_ns, uint32_t reset_counter) {
  if (reset_counter != reset_counter_) {
    reset_counter_ = reset_counter;
    T_sent_w_ = SE3();
    blending_ = false;
  }
  const double dt_s =
      last_ns_ >= 0 ? std::max(0.0, static_cast<double>(t_ns - last_ns_) * 1e-9) : 0.0;
  last_ns_ = t_ns;
  last_step_m_ = 0.0;
  last_step_rad_ = 0.0;
  if (!blending_) return T_w_c;
  // What still separates the pose sent from tracking's, in the camera: shrunk along its twist,
  // so that the camera's extra motion is what the rate allows, whatever its distance from the
  // world's origin.
  const Vector6d remaining = (T_w_c.inverse() * T_sent_w_ * T_w_c).log();
  const double remaining_m = remaining.head<3>().norm();
  const double remaining_rad = remaining.tail<3>().norm();
  const double allowed_m = limits_.rate_m_per_s * dt_s;
  const double allowed_rad = limits_.rate_rad_per_s * dt_s;
  constexpr double kNone = std::numeric_limits<double>::infinity();
  const double fraction = std::min({1.0, remaining_m > 0.0 ? allowed_m / remaining_m : kNone,
                                    remaining_rad > 0.0 ? allowed_rad / remaining_rad : kNone});
  last_step_m_ = fraction * remaining_m;
  last_step_rad_ = fraction * remaining_rad;
  if (fraction >= 1.0) {
    T_sent_w_ = SE3();
    blending_ = false;
    return T_w_c;
  }
  const SE3 T_c_sent = SE3::exp((1.0 - fraction) * remaining);
  T_sent_w_ = T_w_c * T_c_sent * T_w_c.inverse();
  return T_w_c * T_c_sent;
}

}  // namespace rgbdtam

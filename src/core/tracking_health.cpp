#include "rgbdtam/core/tracking_health.hpp"

#include <cmath>
#include <cstdio>

namespace rgbdtam {

bool within_motion_limits(const SE3& T_last_current, double dt_s, const HealthLimits& limits) {
  const double speed = T_last_current.translation().norm() / dt_s;
  const double rate = so3_log(T_last_current.quaternion()).norm() / dt_s;
  return speed <= limits.max_speed_m_s && rate <= limits.max_rotation_rate_rad_s;
}

bool same_pose(const SE3& a, const SE3& b) {
  const SE3 d = a.inverse() * b;
  return within(d, kSamePoseM, kSamePoseRad);
}

double prediction_reach_m(double dt_s, const HealthLimits& limits) {
  return limits.max_acceleration_m_s2 * dt_s * dt_s + kPoseNoiseM;
}

uint32_t failed_health_checks(const TrackResult& r, const HealthContext& context,
                              const HealthLimits& limits) {
  uint32_t failed = 0;
  if (r.state != TrackingState::kOk || r.residuals_used < limits.min_residuals) {
    failed |= kFewResiduals;
  }
  // A NaN anywhere fails its comparison the safe way: written as "not within the limit".
  const bool photometric = (r.terms & kPhotometricTerm) != 0;
  if (photometric && (!(r.photometric_agreement <= limits.max_agreement) ||
                      !(r.photometric_inliers >= limits.min_inliers))) {
    failed |= kPhotometricMisfit;
  }
  if ((r.terms & kGeometricTerm) != 0 && (!(r.geometric_agreement <= limits.max_agreement) ||
                                          !(r.geometric_inliers >= limits.min_inliers))) {
    failed |= kGeometricMisfit;
  }
  if (photometric && context.typical_sigma > 0.0 &&
      !(r.photometric_sigma <= limits.max_sigma_ratio * context.typical_sigma)) {
    failed |= kCostAboveTypical;
  }
  if (!(r.translation_std_m <= limits.max_translation_std_m) ||
      !(r.rotation_std_rad <= limits.max_rotation_std_rad)) {
    failed |= kIllConditioned;
  }
  if (r.depth_degenerate && !(std::sqrt(limits.covariance_scale) * r.weak_direction_std_m <=
                              limits.max_weak_direction_std_m)) {
    failed |= kWeakDirection;
  }
  if (context.dt_s > 0.0) {
    if (!within_motion_limits(context.T_last_current, context.dt_s, limits) ||
        (context.predicted &&
         !(context.from_prediction_m <= prediction_reach_m(context.dt_s, limits)))) {
      failed |= kTooFast;
    }
  }
  if (!r.T_k_c.translation().allFinite() || !r.T_k_c.quaternion().coeffs().allFinite()) {
    failed |= kFewResiduals;
  }
  return failed;
}

namespace {
template <typename T>
uint64_t sampled_fingerprint_of(const T* values, int count) {
  constexpr int kStride = 16;
  uint64_t h = 14695981039346656037ull;
  for (int i = 0; i < count; i += kStride) {
    h = (h ^ static_cast<uint64_t>(values[i])) * 1099511628211ull;
  }
  return h;
}
}  // namespace

uint64_t sampled_fingerprint(const uint16_t* values, int count) {
  return sampled_fingerprint_of(values, count);
}

uint64_t sampled_fingerprint(const uint8_t* values, int count) {
  return sampled_fingerprint_of(values, count);
}

bool FrozenDepthCheck::frozen(const uint16_t* depth, int64_t depth_stamp_ns, const uint8_t* gray,
                              int pixels) {
  const uint64_t d = sampled_fingerprint(depth, pixels);
  const uint64_t g = sampled_fingerprint(gray, pixels);
  const bool repeated = has_previous_ && depth_stamp_ns != stamp_ns_ && d == depth_ && g != gray_;
  repeats_ = repeated ? repeats_ + 1 : 0;
  depth_ = d;
  gray_ = g;
  stamp_ns_ = depth_stamp_ns;
  has_previous_ = true;
  return repeats_ >= kFrozenAfterRepeats;
}

void describe_health(uint32_t failed, char* buf, int size) {
  static constexpr struct {
    uint32_t bit;
    const char* name;
  } kNames[] = {{kFewResiduals, "few residuals"},
                {kPhotometricMisfit, "photometric misfit"},
                {kGeometricMisfit, "geometric misfit"},
                {kCostAboveTypical, "cost above typical"},
                {kIllConditioned, "ill-conditioned"},
                {kTooFast, "too fast"},
                {kWeakDirection, "weak direction"},
                {kAmbiguous, "ambiguous"},
                {kDepthFrozen, "depth frozen"},
                {kBeyondSearch, "beyond search"},
                {kDepthUnits, "depth units"}};
  if (size <= 0) return;
  if (failed == 0) {
    std::snprintf(buf, static_cast<size_t>(size), "healthy");
    return;
  }
  buf[0] = '\0';
  int used = 0;
  for (const auto& n : kNames) {
    if ((failed & n.bit) == 0) continue;
    const int w = std::snprintf(buf + used, static_cast<size_t>(size - used), "%s%s",
                                used > 0 ? ", " : "", n.name);
    if (w < 0 || used + w >= size) break;  // truncated by snprintf, still terminated
    used += w;
  }
}

}  // namespace rgbdtam

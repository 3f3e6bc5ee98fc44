#include "rgbdtam/runtime/tracking/pose_search.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdtam {
namespace {
// Initial guesses of the wider basin: the prediction turned about each camera axis in steps of
// 4 degrees, as far as the rotation-rate limit allows since the last valid pose. The coarsest
// level (80x60) converges from about 2-3 of its pixels, some 2.5 degrees at a 525 px focal
// length, so 4-degree steps leave no gap.
constexpr double kGuessTurnStepRad = 4.0 * M_PI / 180.0;
constexpr int kMaxGuessTurns = 4;  // 16 degrees: 480 deg/s over one 30 Hz frame
constexpr int kMaxGuesses = 5 + 6 * kMaxGuessTurns;
}  // namespace

void PoseSearch::allocate(const Keyframe& capacity_model, const TrackerOptions& tracker,
                          const HealthLimits& health) {
  health_ = health;
  tracker_.allocate(capacity_model, tracker);
}

uint32_t PoseSearch::failed_checks(const TrackResult& r, Keyframe* kf, const FramePyramid& frame,
                                   const MotionState& motion, int64_t t_ns) {
  const HealthContext context = motion.context(kf->T_w_k * r.T_k_c, t_ns, typical_.photometric[0]);
  uint32_t failed = failed_health_checks(r, context, health_);
  // From an uncertain guess (after a loss) the planes of a plain scene can fit another place
  // too: the same test, along the direction the depth determines worst.
  const bool uncertain_guess = !motion.previous_valid();
  if (failed == 0 && (r.depth_degenerate || uncertain_guess) &&
      !unique_along_weak_direction(r, kf, frame)) {
    failed |= kWeakDirection;
  }
  return failed;
}

bool PoseSearch::unique_along_weak_direction(const TrackResult& r, Keyframe* kf,
                                             const FramePyramid& frame) {
  // A direction the depth leaves free rests on the image alone, and a texture-poor image can
  // hold several minima along it within one frame's motion (doors along a corridor). The pose
  // stands only if tracking from starts half a frame's largest motion to either side along that
  // direction comes back to it.
  constexpr double kFramePeriodS = 1.0 / 30.0;
  constexpr double kSameM = 0.02, kSameRad = 1.0 * M_PI / 180.0;
  const double step_m = 0.5 * health_.max_speed_m_s * kFramePeriodS;
  for (const double sign : {-1.0, 1.0}) {
    const SE3 start = r.T_k_c * SE3::exp(r.weak_direction * (sign * step_m));
    const TrackResult other = tracker_.track(*kf, frame, start, typical_, r.terms);
    const SE3 d = r.T_k_c.inverse() * other.T_k_c;
    if (!(d.translation().norm() <= kSameM && so3_log(d.quaternion()).norm() <= kSameRad)) {
      return false;
    }
  }
  return true;
}

Attempt PoseSearch::track(Keyframe* kf, const FramePyramid& frame, const SE3& T_w_guess,
                          const MotionState& motion, int64_t t_ns) {
  Attempt a;
  a.kf = kf;
  a.r = tracker_.track(*kf, frame, kf->T_w_k.inverse() * T_w_guess, typical_);
  a.failed = failed_checks(a.r, kf, frame, motion, t_ns);
  return a;
}

Attempt PoseSearch::first(Keyframe* kf, const FramePyramid& frame, const MotionState& motion,
                          MotionPriors* priors, int64_t t_ns) {
  const SE3 predicted = motion.predict(t_ns);
  SE3 guess;
  if (priors->first_guess(motion, t_ns, predicted, &guess)) {
    Attempt a = track(kf, frame, guess, motion, t_ns);
    if (priors->stands(motion, a.T_w_c(), a.failed == 0)) return a;
  }
  return track(kf, frame, predicted, motion, t_ns);
}

Attempt PoseSearch::from_guesses(Keyframe* kf, const FramePyramid& frame, const MotionState& motion,
                                 const MotionPriors& priors, int64_t t_ns) {
  const SE3 predicted = motion.predict(t_ns);
  SE3 guesses[kMaxGuesses];
  int n = 0;
  const SE3 T_k_w = kf->T_w_k.inverse();
  auto add = [&](const SE3& T_w_c) { guesses[n++] = T_k_w * T_w_c; };
  add(predicted);
  SE3 turned;
  if (priors.basin_guess(motion, t_ns, predicted, &turned)) add(turned);
  add(motion.T_w_last());  // the camera stopped
  const double dt = motion.seconds_since_last(t_ns);
  add(motion.extrapolate(0.5 * dt));  // it slowed down ...
  add(motion.extrapolate(2.0 * dt));  // ... or sped up
  const double reach = health_.max_rotation_rate_rad_s * dt;
  const int turns =
      std::clamp(static_cast<int>(std::ceil(reach / kGuessTurnStepRad)), 1, kMaxGuessTurns);
  for (int step = 1; step <= turns; ++step) {
    const double turn = step * kGuessTurnStepRad;
    for (int axis = 0; axis < 3; ++axis) {
      for (const double sign : {-1.0, 1.0}) {
        add(predicted * SE3(so3_exp(Vector3d::Unit(axis) * (sign * turn)), Vector3d::Zero()));
      }
    }
  }
  Attempt a;
  a.kf = kf;
  a.r = tracker_.track_best(*kf, frame, guesses, n, typical_);
  a.failed = failed_checks(a.r, kf, frame, motion, t_ns);
  return a;
}

Attempt PoseSearch::without_misfit_term(const Attempt& a, const FramePyramid& frame,
                                        const MotionState& motion, int64_t t_ns) {
  // A term that does not fit while the other does (blur against a sharp keyframe, depth
  // misregistered or missing) is dropped and the pose solved from the other alone; it is valid
  // only if that term on its own determines the pose.
  const uint32_t misfit = a.failed & (kPhotometricMisfit | kGeometricMisfit);
  if (a.failed == 0 || a.r.terms != kAllTerms ||
      (misfit != kPhotometricMisfit && misfit != kGeometricMisfit)) {
    return a;
  }
  const uint8_t keep = misfit == kPhotometricMisfit ? kGeometricTerm : kPhotometricTerm;
  Attempt b;
  b.kf = a.kf;
  b.r = tracker_.track(*a.kf, frame, a.r.T_k_c, typical_, keep);
  b.failed = failed_checks(b.r, a.kf, frame, motion, t_ns);
  if (b.failed == 0) ++counters_.single_term;
  return b.failed == 0 ? b : a;
}

void PoseSearch::learn_scales(const TrackResult& r) {
  if ((r.terms & kPhotometricTerm) == 0) return;
  for (int l = 0; l < kPyramidLevels; ++l) {
    float& typical = typical_.photometric[l];
    typical = typical == 0.f ? r.level_sigma[l] : 0.95f * typical + 0.05f * r.level_sigma[l];
  }
}

}  // namespace rgbdtam

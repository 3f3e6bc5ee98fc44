#include "rgbdtam/runtime/tracking/pose_search.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rgbdtam {
namespace {
// Initial guesses of the wider basin: the prediction turned about each camera axis in steps of
// 4 degrees, as far as the rotation-rate limit allows since the last valid pose. The coarsest
// level (80x60) converges from about 2-3 of its pixels, some 2.5 degrees at a 525 px focal
// length, so 4-degree steps leave no gap.
constexpr double kGuessTurnStepRad = 4.0 * M_PI / 180.0;
constexpr int kMaxGuessTurns = 4;  // 16 degrees: 480 deg/s over one 30 Hz frame
constexpr int kMaxGuesses = 5 + 6 * kMaxGuessTurns;
// A probe worth refining fits at most this much worse than the pose at the probing level.
constexpr double kProbeRatio = 1.5;
// Two minima fit about as well when their mean costs are within this factor.
constexpr double kAmbiguityRatio = 1.5;
constexpr int kProbeLevel = 2;
constexpr int kMaxProbes = 96;
// A minimum's basin at the probing levels spans about two of their pixels (the coarsest
// converges from 2-3): probes further apart can step over one.
constexpr double kBasinPx = 2.0;
// Candidate poses are compared at the probes' photometric scale.
ReferenceScales probe_scales() {
  ReferenceScales scales;
  for (float& s : scales.photometric) s = kProbeSigma;
  return scales;
}
}  // namespace

void PoseSearch::allocate(const Keyframe& capacity_model, const TrackerOptions& tracker,
                          const HealthLimits& health, double alias_range_m) {
  health_ = health;
  alias_range_m_ = alias_range_m;
  tracker_.allocate(capacity_model, tracker);
}

uint32_t PoseSearch::failed_checks(const TrackResult& r, Keyframe* kf, const FramePyramid& frame,
                                   const MotionState& motion, int64_t t_ns) {
  const HealthContext context = motion.context(kf->T_w_k * r.T_k_c, t_ns, typical_.photometric[0]);
  uint32_t failed = failed_health_checks(r, context, health_);

  // From an uncertain guess (after a loss) the planes of a plain scene can fit another place
  // too: the same test, along the direction the depth determines worst. So must a pose from the
  // depth alone, the image not fitting it: a wall and a floor with a few small things on them
  // look determined by their information, yet a start along the wall settles where it starts.
  const bool uncertain_guess = !motion.previous_valid();
  const bool depth_alone = r.terms == kGeometricTerm;
  if (failed == 0 && (r.depth_degenerate || uncertain_guess || depth_alone) &&
      !unique_along_weak_direction(r, kf, frame, motion, t_ns)) {
    failed |= kWeakDirection;
  }
  return failed;
}

bool PoseSearch::unique_along_weak_direction(const TrackResult& r, Keyframe* kf,
                                             const FramePyramid& frame, const MotionState& motion,
                                             int64_t t_ns) {
  // A direction the depth leaves free rests on the image alone, and a texture-poor image can
  // hold several minima along it within one frame's motion (doors along a corridor). The pose
  // stands unless tracking from starts half a frame's largest motion to either side along that
  // direction finds another pose that passes every check; after a loss, where the pose itself
  // came from an uncertain guess, unless both come back to it.
  const bool uncertain_guess = !motion.previous_valid();
  constexpr double kFramePeriodS = 1.0 / 30.0;
  const double step_m = 0.5 * health_.max_speed_m_s * kFramePeriodS;
  for (const double sign : {-1.0, 1.0}) {
    const SE3 start = r.T_k_c * SE3::exp(r.weak_direction * (sign * step_m));
    if (comes_back(*kf, frame, start, r.T_k_c, r.terms, kProbeLevel)) continue;
    const TrackResult other = tracker_.track(*kf, frame, start, typical_, r.terms);
    if (!same_pose(r.T_k_c, other.T_k_c) &&
        (uncertain_guess ||
         failed_health_checks(
             other, motion.context(kf->T_w_k * other.T_k_c, t_ns, typical_.photometric[0]),
             health_) == 0)) {
      return false;
    }
  }
  return true;
}

bool PoseSearch::comes_back(const Keyframe& kf, const FramePyramid& frame, const SE3& start,
                            const SE3& T_k_c, uint8_t terms, int level) {
  // Back within the distance at which two poses are the same, the start is in the pose's own
  // basin: the finer levels would refine the pose again, so they are spared.
  return same_pose(tracker_.align(kf, frame, start, terms, level), T_k_c);
}

Attempt PoseSearch::judged(Keyframe* kf, const FramePyramid& frame, const TrackResult& r,
                           const MotionState& motion, int64_t t_ns) {
  Attempt a;
  a.kf = kf;
  a.r = r;
  a.failed = failed_checks(r, kf, frame, motion, t_ns);
  if (a.failed == 0) resolve_within_reach(&a, frame, motion, t_ns);
  return a;
}

bool PoseSearch::reach(const MotionState& motion, int64_t t_ns, Reach* out) const {
  if (!motion.has_last() || t_ns <= motion.last_ns()) return false;
  const double dt = motion.seconds_since_last(t_ns);
  if (motion.has_velocity()) {
    out->centre_w = motion.predict(t_ns).translation();
    out->radius_m = prediction_reach_m(dt, health_);
  } else {
    out->centre_w = motion.T_w_last().translation();
    out->radius_m = health_.max_speed_m_s * dt;
  }
  return true;
}

double PoseSearch::fit(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c, int level,
                       const ReferenceScales& scales, uint8_t terms) {
  const double zero = 0.0;
  double cost = 0.0;
  tracker_.profile(kf, frame, T_k_c, Vector6d::Zero(), &zero, 1, level, scales, terms, &cost);
  return cost;
}

int PoseSearch::aliases_within(const Attempt& a, const FramePyramid& frame, const Reach& within,
                               const Probing& probing, Candidate* out) {
  const KeyframeAliases& aliases = a.kf->aliases;
  int n = 0;
  for (int j = 0; j < aliases.count; ++j) {
    for (const double sign : {-1.0, 1.0}) {
      // The pose moved by the alias in the keyframe's frame: the world repeats there, as the
      // keyframe saw it. Seen from this frame it may not (parallax, a part out of view), and
      // what fits clearly worse than the pose is looked at no closer than a probe would be.
      const SE3 T_k_c = SE3(Eigen::Quaterniond::Identity(), sign * aliases.shift_k[j]) * a.r.T_k_c;
      if (((a.kf->T_w_k * T_k_c).translation() - within.centre_w).norm() > within.radius_m) {
        continue;
      }
      const double cost = fit(*a.kf, frame, T_k_c, probing.level, probe_scales(), probing.terms);
      if (cost <= kProbeRatio * probing.pose_cost) out[n++] = {T_k_c, cost};
    }
  }
  return n;
}

void PoseSearch::resolve_within_reach(Attempt* a, const FramePyramid& frame,
                                      const MotionState& motion, int64_t t_ns) {
  Reach within;
  if (!reach(motion, t_ns, &within)) return;
  const Keyframe& kf = *a->kf;
  // The keyframe's aliases were looked for only so far: a reach beyond that could hold others.
  if (kf.aliases.count > 0 && within.radius_m > alias_range_m_) {
    a->failed |= kAmbiguous;
    ++counters_.ambiguous;
    return;
  }
  Probing probing;
  if (!probing_for(*a, frame, within, &probing)) {
    // Another minimum could lie between the probes: nothing says this pose is the one.
    a->failed |= kBeyondSearch;
    ++counters_.beyond_search;
    return;
  }
  // Candidates: the keyframe's aliases within reach, each comparable one looked at; then the
  // other minima the probes find, the comparable ones.
  Candidate* candidates = candidates_;
  const int from_aliases = aliases_within(*a, frame, within, probing, candidates);
  const int probed = probe_within(*a, frame, within, probing, candidates + from_aliases,
                                  kMaxCandidates - from_aliases);
  if (from_aliases + probed == 0) return;
  // Each refined as tracking would, from there; the distinct healthy minima are compared at
  // the finest level. A probed one not refined (too many) could be the right one: ambiguous.
  const ReferenceScales scales = probe_scales();
  Attempt best = *a;
  double best_cost = fit(kf, frame, a->r.T_k_c, 0, scales, a->r.terms);
  SE3 seen[kMaxCandidates + 1] = {a->r.T_k_c};
  int distinct = 1;
  const int refined = from_aliases + std::min(probed, kMaxRefined);
  for (int i = 0; i < refined; ++i) {
    if (comes_back(kf, frame, candidates[i].T_k_c, a->r.T_k_c, a->r.terms, probing.level)) {
      continue;
    }
    Attempt b;
    b.kf = a->kf;
    b.r = tracker_.track(kf, frame, candidates[i].T_k_c, typical_, a->r.terms);
    b.failed = failed_health_checks(b.r, motion.context(b.T_w_c(), t_ns, typical_.photometric[0]),
                                    health_);
    bool repeated = false;
    for (int k = 0; k < distinct; ++k) repeated = repeated || same_pose(b.r.T_k_c, seen[k]);
    if (b.failed != 0 || repeated) continue;
    seen[distinct++] = b.r.T_k_c;
    const double cost = fit(kf, frame, b.r.T_k_c, 0, scales, a->r.terms);
    if (cost < best_cost) {
      best = b;
      best_cost = cost;
    }
  }
  // Every other minimum is compared with the best on the points both see: by the mean over each
  // one's own points in view, a pose seeing only the best-fitting part of the keyframe would win.
  bool ambiguous = probed > kMaxRefined;
  for (int k = 0; k < distinct && !ambiguous; ++k) {
    if (same_pose(seen[k], best.r.T_k_c)) continue;
    double best_common = 0.0, other_common = 0.0;
    tracker_.fit_on_common_points(kf, frame, best.r.T_k_c, seen[k], 0, scales, a->r.terms,
                                  &best_common, &other_common);
    // Nothing seen by both: nothing says which is right.
    ambiguous = !std::isfinite(best_common) || other_common < kAmbiguityRatio * best_common;
  }
  if (ambiguous) {
    a->failed |= kAmbiguous;
    ++counters_.ambiguous;
    return;
  }
  if (!same_pose(best.r.T_k_c, a->r.T_k_c)) {
    *a = best;
    ++counters_.better_within_reach;
  }
}

bool PoseSearch::probing_for(const Attempt& a, const FramePyramid& frame, const Reach& within,
                             Probing* out) {
  // The scene's depth sets how far a pixel's motion is: probes a pixel apart at 160x120 (a
  // minimum's basin is a pixel or two there), or at 80x60 when the reach needs more than
  // kMaxProbes of them; a reach that even those would not cover a basin apart (a long loss,
  // a near wall) is beyond the search.
  const Keyframe& kf = *a.kf;
  constexpr int kSample = 256;
  float depths[kSample];
  const TrackPoints& pts = kf.photometric(0).size() > 0 ? kf.photometric(0) : kf.geometric[0];
  if (pts.size() == 0) return true;  // nothing to probe with, nor to compare
  const int stride = std::max(1, pts.size() / kSample);
  int n = 0;
  for (int i = 0; i < pts.size() && n < kSample; i += stride) depths[n++] = pts.z()[i];
  std::nth_element(depths, depths + n / 2, depths + n);
  const double depth = depths[n / 2];
  int level = kProbeLevel;
  while (level < kPyramidLevels - 1 &&
         2.0 * within.radius_m / (depth / frame.intrinsics(level).fx_px) > kMaxProbes - 1) {
    ++level;
  }
  const double pixel_m = depth / frame.intrinsics(level).fx_px;
  const double spacing = std::max(pixel_m, 2.0 * within.radius_m / (kMaxProbes - 1));
  if (spacing > kBasinPx * pixel_m) return false;
  // Probed on the image term, whose repeated texture makes the other minima (the depth term,
  // four times the points at these levels, is smooth along them).
  out->level = level;
  out->terms =
      (a.r.terms & kPhotometricTerm) != 0 ? static_cast<uint8_t>(kPhotometricTerm) : a.r.terms;
  out->spacing_m = spacing;
  out->pose_cost = fit(kf, frame, a.r.T_k_c, level, probe_scales(), out->terms);
  return true;
}

int PoseSearch::probe_within(const Attempt& a, const FramePyramid& frame, const Reach& within,
                             const Probing& probing, Candidate* out, int room) {
  if (probing.spacing_m == 0.0) return 0;
  const Keyframe& kf = *a.kf;
  const ReferenceScales scales = probe_scales();
  const Vector3d centre_c = a.T_w_c().inverse() * within.centre_w;
  // Along the directions the depth determines least first: the surfaces' own, along which a
  // texture repeats.
  double lowest = probing.pose_cost;
  int found = 0;
  for (int axis = 0; axis < 3; ++axis) {
    double offsets[kMaxProbes], costs[kMaxProbes];
    int m = 0;
    const double centre = a.r.depth_translation_axes.col(axis).dot(centre_c);
    for (double s = centre - within.radius_m;
         s <= centre + within.radius_m + 1e-9 && m < kMaxProbes; s += probing.spacing_m) {
      offsets[m++] = s;
    }
    Vector6d d = Vector6d::Zero();
    d.head<3>() = a.r.depth_translation_axes.col(axis);
    tracker_.profile(kf, frame, a.r.T_k_c, d, offsets, m, probing.level, scales, probing.terms,
                     costs);
    for (int i = 0; i < m && found < room; ++i) {
      const bool minimum =
          (i == 0 || costs[i] <= costs[i - 1]) && (i == m - 1 || costs[i] <= costs[i + 1]);
      if (!minimum || std::fabs(offsets[i]) < kSamePoseM) continue;
      out[found++] = {a.r.T_k_c * SE3(Eigen::Quaterniond::Identity(), d.head<3>() * offsets[i]),
                      costs[i]};
      lowest = std::min(lowest, costs[i]);
    }
  }
  // Worth a closer look: those that fit about as well as the best at the probing level.
  std::sort(out, out + found,
            [](const Candidate& x, const Candidate& y) { return x.cost < y.cost; });
  while (found > 0 && !(out[found - 1].cost <= kProbeRatio * lowest)) --found;
  return found;
}

Attempt PoseSearch::track(Keyframe* kf, const FramePyramid& frame, const SE3& T_w_guess,
                          const MotionState& motion, int64_t t_ns) {
  return judged(kf, frame, tracker_.track(*kf, frame, kf->T_w_k.inverse() * T_w_guess, typical_),
                motion, t_ns);
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
  ++counters_.wider_searches;
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
  return judged(kf, frame, tracker_.track_best(*kf, frame, guesses, n, typical_), motion, t_ns);
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
  const Attempt b =
      judged(a.kf, frame, tracker_.track(*a.kf, frame, a.r.T_k_c, typical_, keep), motion, t_ns);
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

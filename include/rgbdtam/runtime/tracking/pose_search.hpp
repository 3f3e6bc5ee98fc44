#pragma once
// The search for a frame's pose against a keyframe: the tracker from one guess or from the
// wider basin's several, the health checks each result must pass, the uniqueness test along a
// direction the depth leaves free, and the typical photometric scales that healthy frames
// teach. It decides nothing about keyframes or outputs. Thread: the tracker's.

#include <cstdint>

#include "rgbdtam/core/keyframe_aliases.hpp"
#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/core/tracking_health.hpp"
#include "rgbdtam/runtime/tracking/motion_priors.hpp"
#include "rgbdtam/runtime/tracking/motion_state.hpp"

namespace rgbdtam {

// A tracking result against one keyframe and the health checks it failed (0: healthy).
struct Attempt {
  Keyframe* kf = nullptr;
  TrackResult r;
  uint32_t failed = ~0u;
  SE3 T_w_c() const { return kf->T_w_k * r.T_k_c; }
};

struct SearchCounters {
  uint32_t single_term = 0;          // frames whose pose came from one term, the other not fitting
  uint32_t better_within_reach = 0;  // poses replaced by a clearly better one within reach
  uint32_t ambiguous = 0;            // poses with another within reach that fits about as well
  uint32_t beyond_search = 0;        // poses with a reach too wide to search for other minima
  uint32_t wider_searches = 0;       // wider-basin searches run (tens of trackings each)
};

class PoseSearch {
 public:
  // alias_range_m: how far the keyframes' aliases are looked for.
  void allocate(const Keyframe& capacity_model, const TrackerOptions& tracker,
                const HealthLimits& health, double alias_range_m);

  // From one guess of the camera in the world.
  Attempt track(Keyframe* kf, const FramePyramid& frame, const SE3& T_w_guess,
                const MotionState& motion, int64_t t_ns);
  // From the prediction, turned by a prior where one applies and the image agrees.
  Attempt first(Keyframe* kf, const FramePyramid& frame, const MotionState& motion,
                MotionPriors* priors, int64_t t_ns);
  // The wider basin: several initial guesses screened at the coarsest level.
  Attempt from_guesses(Keyframe* kf, const FramePyramid& frame, const MotionState& motion,
                       const MotionPriors& priors, int64_t t_ns);
  // A term that does not fit while the other does is dropped, where the other alone
  // determines the pose.
  Attempt without_misfit_term(const Attempt& a, const FramePyramid& frame,
                              const MotionState& motion, int64_t t_ns);
  // What a keyframe sees of the frame at a pose, without optimising.
  double visible_at(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c) {
    return tracker_.visible_at(kf, frame, T_k_c);
  }
  // A healthy pose's scales teach what is typical.
  void learn_scales(const TrackResult& r);
  // Another search's, to judge as it does (the local window's measurement).
  const ReferenceScales& typical_scales() const { return typical_; }
  void use_scales(const ReferenceScales& typical) { typical_ = typical; }

  const SearchCounters& counters() const { return counters_; }

 private:
  // The result's health checks and, for a healthy one, the other minima within reach.
  Attempt judged(Keyframe* kf, const FramePyramid& frame, const TrackResult& r,
                 const MotionState& motion, int64_t t_ns);
  uint32_t failed_checks(const TrackResult& r, Keyframe* kf, const FramePyramid& frame,
                         const MotionState& motion, int64_t t_ns);
  // Where the camera can be at t_ns: within the reach of its acceleration around the
  // prediction or, without a velocity, of its speed around the last pose; false before any.
  struct Reach {
    Vector3d centre_w;
    double radius_m = 0.0;
  };
  bool reach(const MotionState& motion, int64_t t_ns, Reach* out) const;
  // A pose another minimum could be, and how well it fits at the probing level.
  struct Candidate {
    SE3 T_k_c;
    double cost = 0.0;
  };
  // Where the candidates within reach are looked at: the level and term, the probes' spacing
  // (0: no points to probe with) and how well the pose itself fits there.
  struct Probing {
    int level = 0;
    uint8_t terms = 0;
    double spacing_m = 0.0;
    double pose_cost = 0.0;
  };
  // False when the reach is too wide for probes to step on every minimum in it.
  bool probing_for(const Attempt& a, const FramePyramid& frame, const Reach& within, Probing* out);
  // The pose moved by each of the keyframe's aliases that lands within reach and fits about as
  // well as the pose at the probing level, into out.
  int aliases_within(const Attempt& a, const FramePyramid& frame, const Reach& within,
                     const Probing& probing, Candidate* out);
  // The other minima probes along the surfaces' directions find within reach that fit about
  // as well as the best at the probing level, best first; at most room of them.
  int probe_within(const Attempt& a, const FramePyramid& frame, const Reach& within,
                   const Probing& probing, Candidate* out, int room);
  // Looks for the other minima within reach along the camera's axes: a clearly better one
  // replaces the pose; one that fits about as well makes it ambiguous.
  void resolve_within_reach(Attempt* a, const FramePyramid& frame, const MotionState& motion,
                            int64_t t_ns);
  // How well the keyframe's points fit the frame at a pose: their mean robust cost at fixed
  // scales, at one level.
  double fit(const Keyframe& kf, const FramePyramid& frame, const SE3& T_k_c, int level,
             const ReferenceScales& scales, uint8_t terms);
  // Whether tracking from start would find T_k_c again: the coarse levels, down to `level`,
  // bring it back there.
  bool comes_back(const Keyframe& kf, const FramePyramid& frame, const SE3& start, const SE3& T_k_c,
                  uint8_t terms, int level);
  bool unique_along_weak_direction(const TrackResult& r, Keyframe* kf, const FramePyramid& frame,
                                   const MotionState& motion, int64_t t_ns);

  // Aliases within reach (both signs) and local minima of three profiles.
  static constexpr int kMaxCandidates = 2 * KeyframeAliases::kMax + 3 * 16;
  static constexpr int kMaxRefined = 4;  // probed candidates refined by tracking

  Tracker tracker_;
  Candidate candidates_[kMaxCandidates];
  HealthLimits health_;
  double alias_range_m_ = 0.0;
  ReferenceScales typical_;  // slow averages over healthy frames
  SearchCounters counters_;
};

}  // namespace rgbdtam

#pragma once
// The search for a frame's pose against a keyframe: the tracker from one guess or from the
// wider basin's several, the health checks each result must pass, the uniqueness test along a
// direction the depth leaves free, and the typical photometric scales that healthy frames
// teach. It decides nothing about keyframes or outputs. Thread: the tracker's.

#include <cstdint>

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
  uint32_t single_term = 0;  // frames whose pose came from one term, the other not fitting
};

class PoseSearch {
 public:
  void allocate(const Keyframe& capacity_model, const TrackerOptions& tracker,
                const HealthLimits& health);

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

  const SearchCounters& counters() const { return counters_; }

 private:
  uint32_t failed_checks(const TrackResult& r, Keyframe* kf, const FramePyramid& frame,
                         const MotionState& motion, int64_t t_ns);
  bool unique_along_weak_direction(const TrackResult& r, Keyframe* kf, const FramePyramid& frame);

  Tracker tracker_;
  HealthLimits health_;
  ReferenceScales typical_;  // slow averages over healthy frames
  SearchCounters counters_;
};

}  // namespace rgbdtam

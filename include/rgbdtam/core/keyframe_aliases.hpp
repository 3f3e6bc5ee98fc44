#pragma once
// Finds a keyframe's aliases: the shifts of its camera along the surfaces it sees at which its
// own image fits itself about as well as unshifted. Found once per keyframe (by the keyframe
// builder), so that tracking needs to look only at the few that fall within the camera's reach.
// Sized in allocate(); find() never allocates.

#include "rgbdtam/core/tracker.hpp"

namespace rgbdtam {

// The photometric scale at which poses a probe apart are compared: what sampling alone leaves,
// a probe up to a quarter of a pixel off an edge of 0.4 contrast (a seam, a grout line) missing
// it by 0.1 in intensity. A finer scale would see only exact alignments between probes; a
// coarser one, a single bowl.
constexpr float kProbeSigma = 0.1f;

class KeyframeAliasFinder {
 public:
  static size_t bytes_needed(const PinholeIntrinsics& finest, const TrackerOptions& opt) {
    return Tracker::scratch_bytes(finest, opt);
  }
  void allocate(const Keyframe& capacity_model, const TrackerOptions& opt);
  // own: the keyframe's frame; range_m: how far to look along each surface direction.
  void find(const FramePyramid& own, const Keyframe& kf, double range_m, KeyframeAliases* out);

 private:
  static constexpr int kMaxProbes = 1024;  // per direction
  Tracker tracker_;                        // its profile() is the self-fit
  double offsets_[kMaxProbes] = {}, costs_[kMaxProbes] = {}, overlap_[kMaxProbes] = {};
};

// The translation directions (keyframe or camera frame, unit columns) the points' depth
// residuals determine least to most, from their Jacobians at the keyframe: the surfaces' own
// directions first. The camera's axes without depth points.
Matrix3d depth_translation_axes(const TrackPoints& geometric);

}  // namespace rgbdtam

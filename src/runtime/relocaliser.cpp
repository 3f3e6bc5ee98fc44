#include "rgbdtam/runtime/relocaliser.hpp"

namespace rgbdtam {
namespace {
// The camera may have moved this far from its last valid pose while lost: the places within
// it are searched by geometry as well as by appearance.
constexpr double kSearchRadiusM = 0.5;
}  // namespace

void Relocaliser::allocate(const Params& params) {
  params_ = params;
  params_.health = health_limits(params);
  recognizer_.allocate(params);
  limits_ = VerificationLimits::of(params);
  aligner_.allocate(params.camera, params.sensor.depth_factor, params.sensor.depth_range,
                    tracking_options(params));
  view_.allocate(params.camera);
}

size_t Relocaliser::bytes_needed(const Params& params) {
  return PlaceRecognizer::bytes_needed(params) + View::bytes(params.camera) +
         ViewAligner::bytes_needed(params.camera, tracking_options(params));
}

Relocalisation Relocaliser::find(const FramePyramid& frame, const SE3* T_w_last, PlaceStore* places,
                                 const Vocabulary& vocabulary) {
  recognizer_.describe(frame.gray(0), frame.inverse_depth(0), frame.intrinsics(0), vocabulary);
  capture_view(frame, &view_);
  aligner_.set(1, view_);
  Relocalisation best;
  std::lock_guard<std::mutex> lock(places->mutex());
  PlaceCandidate candidates[kAppearance + kGeometric];
  int n = recognizer_.add_appearance_candidates(*places, nullptr, nullptr, kAppearance, limits_,
                                                candidates, 0);
  // The places nearest the last valid pose.
  for (int g = 0; g < kGeometric && T_w_last != nullptr; ++g) {
    int nearest = -1;
    double nearest_distance = kSearchRadiusM;
    for (int i = 0; i < places->size(); ++i) {
      const int slot = places->handle(i).slot;
      bool chosen = false;
      for (int k = 0; k < n; ++k) chosen |= candidates[k].slot == slot;
      const SE3 d = places->at_slot(slot).T_w_k.inverse() * *T_w_last;
      const double distance = ranking_distance_m(d);
      if (!chosen && distance < nearest_distance) nearest = slot, nearest_distance = distance;
    }
    if (nearest < 0) break;
    candidates[n] = PlaceCandidate();
    candidates[n++].slot = nearest;
  }
  // Places that each show the frame somewhere else: a repeated scene, and no fix.
  bool several_poses = false;
  for (int i = 0; i < n; ++i) {
    PlaceCandidate& c = candidates[i];
    const PlaceRecord& place = places->at_slot(c.slot);
    if (place.repeats) continue;
    // Where the camera was last, and where the place was seen: the outage's motion is unknown.
    if (T_w_last != nullptr) c.add_guess(place.T_w_k.inverse() * *T_w_last);
    c.add_guess(SE3());
    aligner_.set(0, place.view);
    const ViewAlignment a = aligner_.align(c.guesses, c.guess_count, params_.health);
    if (!shows_same_place(a)) continue;
    if (best.found && !same_pose(best.T_w_c(), place.T_w_k * a.T_a_b)) several_poses = true;
    // Of several places, the one sharing the most of the frame.
    if (best.found && a.forward.overlap <= best.alignment.forward.overlap) continue;
    best.found = true;
    best.place_id = place.keyframe_id;
    best.T_w_place = place.T_w_k;
    best.alignment = a;
  }
  if (several_poses) return Relocalisation();
  return best;
}

}  // namespace rgbdtam

// The tracker's side of loop closure: new keyframes out to the loop module, its corrections
// adopted between frames, and lost frames looked up in the places (relocalisation).
#include <algorithm>
#include <cstring>

#include "rgbdtam/runtime/tracking_pipeline.hpp"

namespace rgbdtam {

void TrackingPipeline::connect_loop(LoopQueue* keyframes, CorrectionQueue* corrections,
                                    PlaceStore* places, const Vocabulary* vocabulary) {
  loop_queue_ = keyframes;
  corrections_ = corrections;
  places_ = places;
  vocabulary_ = vocabulary;
  relocaliser_.allocate(params_);
  relocalisation_limits_ = VerificationLimits::of(params_);
}

void TrackingPipeline::offer_to_loop(const Keyframe& kf, uint32_t reference_id,
                                     const PoseEstimate& pose, bool after_reset) {
  if (loop_queue_ == nullptr) return;
  LoopKeyframe* slot = loop_queue_->begin_push();
  if (slot == nullptr) {
    ++counters_.loop_dropped_keyframes;
    return;
  }
  slot->keyframe_id = kf.id;
  slot->reference_id = reference_id;
  slot->after_reset = after_reset;
  slot->corrections_adopted = corrections_adopted_;
  slot->timestamp_ns = kf.timestamp_ns;
  slot->T_w_k = kf.T_w_k;
  slot->information = pose.information;
  std::memcpy(slot->gray.data(), frame().gray(0).data(), sizeof(float) * slot->gray.size());
  std::memcpy(slot->inverse_depth.data(), frame().inverse_depth(0).data(),
              sizeof(float) * slot->inverse_depth.size());
  loop_queue_->publish();
}

bool TrackingPipeline::relocalise(const SensorFrame& frame, PoseEstimate* out) {
  if (places_ == nullptr || !params_.loop.relocalise || !this->frame().has_depth()) return false;
  // More candidates than a loop query verifies: a lost frame has already missed its deadline's
  // use, and has no second query to be consistent with.
  constexpr int kCandidates = 8;
  relocaliser_.describe(this->frame().gray(0), this->frame().inverse_depth(0),
                        this->frame().intrinsics(0), *vocabulary_);
  RigidRansacResult best;
  uint32_t place_id = 0;
  SE3 T_w_place;
  {
    std::lock_guard<std::mutex> lock(places_->mutex());
    PlaceMatch matches[kCandidates];
    const int n =
        places_->database().query(relocaliser_.bow(), nullptr, nullptr, matches, kCandidates);
    for (int i = 0; i < n; ++i) {
      const PlaceRecord& place = places_->at_slot(matches[i].slot);
      const RigidRansacResult fit = relocaliser_.verify(place, relocalisation_limits_);
      if (fit.inliers > best.inliers) {
        best = fit;
        place_id = place.keyframe_id;
        T_w_place = place.T_w_k;
      }
    }
  }
  if (best.inliers == 0) return false;
  const SE3 T_w_c = T_w_place * best.T_b_a;
  // The camera must have been able to get there since the last valid pose: a frame that
  // shows another place for an instant (a glitch, a reflection) stays lost.
  const double dt = static_cast<double>(frame.timestamp_ns - last_ns_) * 1e-9;
  if (has_last_ &&
      !(dt > 0.0 && within_motion_limits(T_w_last_.inverse() * T_w_c, dt, params_.health))) {
    return false;
  }
  Keyframe* kf = nullptr;
  for (int i = 0; i < pool_->size() && kf == nullptr; ++i) {
    if (pool_->at(i).id == place_id) kf = &pool_->at(i);
  }
  if (kf != nullptr) {
    // Refined directly against the place's keyframe; it must pass every health check.
    adopt_map(kf);
    const Attempt a = track_against(kf, T_w_c, frame.timestamp_ns);
    if (a.failed != 0) return false;
    velocity_.setZero();  // none carries across a loss
    has_last_ = false;
    accept(a, frame, out);
  } else {
    // Its dense keyframe is gone: this frame becomes one, at the verified pose. Nothing dense
    // can confirm that pose, so the 3-D match must be twice as strong.
    if (best.inliers < 2 * relocalisation_limits_.min_inliers) return false;
    start_keyframe(frame.timestamp_ns, T_w_c, out, true);
    ++counters_.relocalised_on_new_keyframe;
    out->T_w_c = T_w_c;
    out->flags |= kPoseValid;
    T_w_last_ = T_w_c;
    last_ns_ = frame.timestamp_ns;
    has_last_ = true;
    velocity_.setZero();
    fallback_ = nullptr;
    ++counters_.tracked;
  }
  out->flags |= kRelocalised | kReset;
  ++reset_counter_;
  ++counters_.relocalised;
  return true;
}

bool TrackingPipeline::keyframe_pose(uint32_t id, SE3* T_w_k) const {
  for (int i = 0; i < pool_->size(); ++i) {
    if (pool_->at(i).id == id) {
      *T_w_k = pool_->at(i).T_w_k;
      return true;
    }
  }
  return false;
}

void TrackingPipeline::adopt_corrections() {
  if (corrections_ == nullptr) return;
  while (LoopCorrection* c = corrections_->front()) {
    apply_correction(*c);
    corrections_->pop();
  }
}

void TrackingPipeline::apply_correction(const LoopCorrection& c) {
  // Counted as taken even when none of it applies here: the loop module corrects the keyframes
  // it receives by what the tracker has taken.
  ++corrections_adopted_;
  if (c.poses.empty()) return;
  auto corrected = [&](uint32_t id) -> const KeyframePose* {
    const KeyframePose* p =
        std::lower_bound(c.poses.begin(), c.poses.end(), id,
                         [](const KeyframePose& k, uint32_t key) { return k.keyframe_id < key; });
    return p != c.poses.end() && p->keyframe_id == id ? p : nullptr;
  };
  // Each remembered keyframe moves to its corrected pose; a keyframe newer than the correction
  // moves with the newest one the correction knows.
  SE3 newest_delta;
  uint32_t newest_id = 0;
  bool have_newest = false;
  SE3 reference_delta;
  bool have_reference = false;
  for (int i = 0; i < pool_->size(); ++i) {
    Keyframe& kf = pool_->at(i);
    const KeyframePose* p = corrected(kf.id);
    if (p == nullptr) continue;
    const SE3 delta = p->T_w_k * kf.T_w_k.inverse();
    if (!have_newest || kf.id > newest_id)
      newest_delta = delta, newest_id = kf.id, have_newest = true;
    if (&kf == reference_) reference_delta = delta, have_reference = true;
    kf.T_w_k = p->T_w_k;
  }
  if (!have_newest) return;
  const uint32_t last_known = c.poses[c.poses.size() - 1].keyframe_id;
  for (int i = 0; i < pool_->size(); ++i) {
    Keyframe& kf = pool_->at(i);
    if (kf.id > last_known) kf.T_w_k = newest_delta * kf.T_w_k;
    if (&kf == reference_ && kf.id > last_known)
      reference_delta = newest_delta, have_reference = true;
  }
  for (LocalMap& m : local_maps_) m.T_w_k = newest_delta * m.T_w_k;
  const SE3 before = T_w_last_;
  T_w_last_ = (have_reference ? reference_delta : newest_delta) * T_w_last_;
  // Poses either side of a large jump are not comparable: as after a restart, none is
  // reported over the window in which a consumer differences poses.
  const SE3 jump = before.inverse() * T_w_last_;
  if (jump.translation().norm() > params_.loop.max_reported_jump_m ||
      so3_log(jump.quaternion()).norm() > params_.loop.max_reported_jump_rad) {
    withhold_until_ns_ = last_ns_ + params_.reset_after_lost_ns;
  }
  ++reset_counter_;
  ++counters_.loop_corrections;
  pending_flags_ |= kLoopCorrected | kReset;
}

}  // namespace rgbdtam

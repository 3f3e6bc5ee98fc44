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
}

void TrackingPipeline::start_in_loaded_map(uint32_t next_keyframe_id) {
  RGBDTAM_ASSERT(places_ != nullptr && counters_.frames == 0, "a map is loaded before tracking");
  next_keyframe_id_ = next_keyframe_id;
  localising_ = true;
}

void TrackingPipeline::find_in_loaded_map(const SensorFrame& frame, PoseEstimate* out) {
  // The map's world frame is the only one: until the camera is found in it, there is no pose
  // (a restart would begin a world frame of its own).
  if (!relocalise(frame, out)) {
    out->flags |= kLocalising;
    out->reset_counter = reset_counter_;
    return;
  }
  localising_ = false;
  out->reset_counter = reset_counter_;
  if (!pending_keyframe_.due) offer_to_mapper(*out, this->frame(), nullptr);
  current_ = 1 - current_;
  last_valid_frame_kept_ = true;
  previous_valid_ = true;
}

TrackingPipeline::KeyframeLink TrackingPipeline::odometry_link(
    const SE3& T_w_c, const Matrix6d& tracker_information) const {
  KeyframeLink link;
  link.reference_id = reference_->id;
  link.kind = EdgeKind::kOdometry;
  link.T_reference_keyframe = reference_->T_w_k.inverse() * T_w_c;
  link.information = graph_information(tracker_information, link.T_reference_keyframe);
  return link;
}

TrackingPipeline::KeyframeLink TrackingPipeline::restart_link() const {
  KeyframeLink link;
  link.reference_id = reference_ != nullptr ? reference_->id : next_keyframe_id_;
  return link;
}

LoopKeyframe* TrackingPipeline::loop_slot() {
  if (loop_queue_ == nullptr) return nullptr;
  LoopKeyframe* slot = loop_queue_->begin_push();
  if (slot == nullptr) ++counters_.loop_dropped_keyframes;
  return slot;
}

void TrackingPipeline::offer_to_loop(const Keyframe& kf, const KeyframeLink& link,
                                     const FramePyramid& f) {
  LoopKeyframe* slot = loop_slot();
  if (slot == nullptr) return;
  slot->kind = LoopKeyframe::Kind::kKeyframe;
  slot->keyframe_id = kf.id;
  slot->reference_id = link.reference_id;
  slot->reference_edge = link.kind;
  slot->corrections_adopted = corrections_adopted_;
  slot->timestamp_ns = kf.timestamp_ns;
  slot->T_w_k = kf.T_w_k;
  slot->T_reference_keyframe = link.T_reference_keyframe;
  slot->information = link.information;
  std::memcpy(slot->gray.data(), f.gray(0).data(), sizeof(float) * slot->gray.size());
  std::memcpy(slot->inverse_depth.data(), f.inverse_depth(0).data(),
              sizeof(float) * slot->inverse_depth.size());
  capture_view(f, &slot->view);
  loop_queue_->publish();
}

void TrackingPipeline::offer_reuse_to_loop(const Attempt& left, const Attempt& taken) {
  LoopKeyframe* slot = loop_slot();
  if (slot == nullptr) return;
  // The frame was tracked against both: T_left_taken = T_left_c T_taken_c^-1.
  const SE3& T_left_c = left.r.T_k_c;
  const SE3& T_taken_c = taken.r.T_k_c;
  slot->kind = LoopKeyframe::Kind::kReuse;
  slot->keyframe_id = taken.kf->id;
  slot->reference_id = left.kf->id;
  slot->reference_edge = EdgeKind::kReuse;
  slot->T_reference_keyframe = T_left_c * T_taken_c.inverse();
  slot->information = information_through(
      graph_information(left.r.information / params_.covariance_scale, T_left_c),
      graph_information(taken.r.information / params_.covariance_scale, T_taken_c), T_taken_c);
  loop_queue_->publish();
}

bool TrackingPipeline::relocalise(const SensorFrame& frame, PoseEstimate* out) {
  // A relocalised frame may become a keyframe: it waits until none is being built.
  if (places_ == nullptr || !params_.loop.relocalise || !this->frame().has_depth() ||
      !building_->idle()) {
    return false;
  }
  const Relocalisation found =
      relocaliser_.find(this->frame(), has_last_ ? &T_w_last_ : nullptr, places_, *vocabulary_);
  if (!found.found) return false;
  const SE3 T_w_c = found.T_w_c();
  // The camera must have been able to get there since the last valid pose: a frame that
  // shows another place for an instant (a glitch, a reflection) stays lost.
  const double dt = static_cast<double>(frame.timestamp_ns - last_ns_) * 1e-9;
  if (has_last_ &&
      !(dt > 0.0 && within_motion_limits(T_w_last_.inverse() * T_w_c, dt, params_.health))) {
    return false;
  }
  Keyframe* kf = nullptr;
  for (int i = 0; i < pool_->size() && kf == nullptr; ++i) {
    if (pool_->at(i).id == found.place_id) kf = &pool_->at(i);
  }
  Attempt a;
  if (kf != nullptr) {
    // Refined at full resolution against the place's dense keyframe, where it still is.
    adopt_map(kf);
    a = track_against(kf, T_w_c, frame.timestamp_ns);
  } else {
    ++counters_.relocalised_past_the_pool;
  }
  velocity_.setZero();  // none carries across a loss
  if (a.failed == 0) {
    has_last_ = false;
    accept(a, frame, out);
  } else {
    // The frame becomes a keyframe at the verified pose, tied to the place by the alignment
    // where it measures the pose well enough for the map (else the loop module ties it).
    KeyframeLink link = restart_link();
    if (measures_pose(found.alignment)) {
      link.reference_id = found.place_id;
      link.kind = EdgeKind::kRelocalisation;
      link.T_reference_keyframe = found.alignment.T_a_b;
      link.information =
          graph_information(found.alignment.forward.information / params_.covariance_scale,
                            link.T_reference_keyframe);
    }
    fallback_ = nullptr;
    (void)ask_for_keyframe(T_w_c, link, true, out);
    ++counters_.relocalised_on_new_keyframe;
    out->T_w_c = T_w_c;
    out->flags |= kPoseValid;
    T_w_last_ = T_w_c;
    last_ns_ = frame.timestamp_ns;
    has_last_ = true;
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

#include "rgbdtam/runtime/tracking/loop_link.hpp"

#include <cstring>

#include "rgbdtam/core/pose_graph.hpp"

namespace rgbdtam {

void LoopLink::connect(const Params& params, LoopQueue* keyframes, CorrectionQueue* corrections,
                       PlaceStore* places, const Vocabulary* vocabulary) {
  loop_queue_ = keyframes;
  corrections_ = corrections;
  places_ = places;
  vocabulary_ = vocabulary;
  relocaliser_.allocate(params);
}

LoopKeyframe* LoopLink::slot() {
  if (loop_queue_ == nullptr) return nullptr;
  LoopKeyframe* slot = loop_queue_->begin_push();
  if (slot == nullptr) ++counters_.loop_dropped_keyframes;
  return slot;
}

void LoopLink::offer_keyframe(const Keyframe& kf, const KeyframeLink& link,
                              const WindowLinks& window, const FramePyramid& f) {
  LoopKeyframe* s = slot();
  if (s == nullptr) return;
  s->kind = LoopKeyframe::Kind::kKeyframe;
  s->keyframe_id = kf.id;
  s->reference_id = link.reference_id;
  s->reference_edge = link.kind;
  s->corrections_adopted = corrections_adopted_;
  s->timestamp_ns = kf.timestamp_ns;
  s->T_w_k = kf.T_w_k;
  s->T_reference_keyframe = link.T_reference_keyframe;
  s->information = link.information;
  s->window_edges = window.count;
  for (int i = 0; i < window.count; ++i) {
    s->window[i] = {window.link[i].reference_id, window.link[i].T_reference_keyframe,
                    window.link[i].information};
  }
  std::memcpy(s->gray.data(), f.gray(0).data(), sizeof(float) * s->gray.size());
  std::memcpy(s->inverse_depth.data(), f.inverse_depth(0).data(),
              sizeof(float) * s->inverse_depth.size());
  capture_view(f, &s->view);
  s->repeats = kf.aliases.count > 0;
  loop_queue_->publish();
}

void LoopLink::offer_reuse(const Attempt& left, const Attempt& taken, double covariance_scale) {
  LoopKeyframe* s = slot();
  if (s == nullptr) return;
  // The frame was tracked against both: T_left_taken = T_left_c T_taken_c^-1.
  const SE3& T_left_c = left.r.T_k_c;
  const SE3& T_taken_c = taken.r.T_k_c;
  s->kind = LoopKeyframe::Kind::kReuse;
  s->keyframe_id = taken.kf->id;
  s->reference_id = left.kf->id;
  s->reference_edge = EdgeKind::kReuse;
  s->T_reference_keyframe = T_left_c * T_taken_c.inverse();
  s->information = information_through(
      graph_information(left.r.information / covariance_scale, T_left_c),
      graph_information(taken.r.information / covariance_scale, T_taken_c), T_taken_c);
  loop_queue_->publish();
}

const LoopCorrection* LoopLink::next_correction() {
  return corrections_ != nullptr ? corrections_->front() : nullptr;
}

void LoopLink::correction_taken() {
  ++corrections_adopted_;
  corrections_->pop();
}

Relocalisation LoopLink::find(const FramePyramid& frame, const SE3* T_w_last) {
  return relocaliser_.find(frame, T_w_last, places_, *vocabulary_);
}

}  // namespace rgbdtam

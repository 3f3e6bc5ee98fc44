// The tracker's keyframes: when a new one is asked for, ordered and adopted, when an earlier one
// is reused, the maps the mapper publishes for them, and the frames it is sent.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "rgbdtam/runtime/tracking_pipeline.hpp"

namespace rgbdtam {

Keyframe* TrackingPipeline::keyframe_from_last_valid_frame() {
  if (fallback_ != nullptr) return fallback_;
  if (!last_valid_frame_kept_ || reference_->timestamp_ns == last_ns_) return nullptr;
  const FramePyramid& last = frames_[1 - current_];
  if (!last.has_depth()) return nullptr;
  fallback_ = pool_->acquire(reference_);
  // Sensor depth only: the mapper never saw this frame's images as a keyframe's.
  builder_.build(last, next_keyframe_id_++, last_ns_, T_w_last_, fallback_);
  ++counters_.keyframes;
  return fallback_;
}

bool TrackingPipeline::reuse_keyframe(const Attempt& current, int64_t t_ns, PoseEstimate* out) {
  // The earlier keyframes nearest to the camera, a radian of rotation counted as 0.3 m.
  constexpr int kMaxCandidates = 16;
  constexpr double kMetresPerRadian = 0.3;
  const SE3 T_w_c = current.T_w_c();
  auto distance = [&](const Keyframe& kf) {
    const SE3 d = kf.T_w_k.inverse() * T_w_c;
    return d.translation().norm() + kMetresPerRadian * so3_log(d.quaternion()).norm();
  };
  Keyframe* candidates[kMaxCandidates];
  int count = 0;
  const int wanted = std::min(params_.reuse_candidates, kMaxCandidates);
  while (count < wanted) {
    Keyframe* nearest = nullptr;
    double nearest_distance = 0.0;
    for (int i = 0; i < pool_->size(); ++i) {
      Keyframe* kf = &pool_->at(i);
      if (kf == reference_ || std::find(candidates, candidates + count, kf) != candidates + count) {
        continue;
      }
      const double d = distance(*kf);
      if (nearest == nullptr || d < nearest_distance) {
        nearest = kf;
        nearest_distance = d;
      }
    }
    if (nearest == nullptr) break;
    candidates[count++] = nearest;
  }
  // Rank the candidates by what they see of this frame at the current estimate; track the best.
  Keyframe* best = nullptr;
  double best_visible = params_.tracker.keyframe_overlap;
  for (int i = 0; i < count; ++i) {
    adopt_map(candidates[i]);
    const double visible =
        tracker_.visible_at(*candidates[i], frame(), candidates[i]->T_w_k.inverse() * T_w_c);
    if (visible >= best_visible) {
      best = candidates[i];
      best_visible = visible;
    }
  }
  if (best == nullptr) return false;
  // Reused when it tracks the frame healthily, sees enough of it and has not moved too far.
  // As the authors' test (points in view, a lenient photometric bound), it does not ask for
  // the appearance the last keyframe had: an older keyframe looks less like the frame, which
  // is the price of its smaller drift (asking for the overlap too left 89 keyframes instead of
  // about 30 on fr1_xyz, and 1.15 cm all-frames ATE).
  const Attempt reused = track_against(best, T_w_c, t_ns);
  if (reused.failed != 0 || reused.r.visible < params_.tracker.keyframe_overlap ||
      reused.r.parallax > params_.tracker.keyframe_parallax) {
    return false;
  }
  offer_reuse_to_loop(current, reused);
  reference_ = best;
  out->T_w_c = reused.T_w_c();
  out->keyframe_id = best->id;
  out->overlap = static_cast<float>(reused.r.overlap);
  out->information = reused.r.information / params_.covariance_scale;
  out->flags |= kKeyframeReused;
  T_w_last_ = out->T_w_c;
  ++counters_.reused;
  return true;
}

bool TrackingPipeline::ask_for_keyframe(const SE3& T_w_k, const KeyframeLink& link, bool to_mapper,
                                        PoseEstimate* out) {
  if (!building_->idle()) return false;
  // Ordered after the pose is out (build_pending_keyframe), from this frame's buffer, which the
  // next frame leaves alone until then.
  out->flags |= kNewKeyframe;
  out->keyframe_id = next_keyframe_id_;
  pending_keyframe_.due = true;
  pending_keyframe_.frame_buffer = current_;
  pending_keyframe_.T_w_k = T_w_k;
  pending_keyframe_.link = link;
  pending_keyframe_.to_mapper = to_mapper;
  return true;
}

void TrackingPipeline::build_pending_keyframe() {
  if (!pending_keyframe_.due) return;
  pending_keyframe_.due = false;
  const FramePyramid& f = frames_[pending_keyframe_.frame_buffer];
  const size_t pixels = static_cast<size_t>(f.gray(0).size());
  std::memcpy(building_->gray_level0().data(), f.gray(0).data(), sizeof(float) * pixels);
  std::memcpy(building_->inverse_depth_level0().data(), f.inverse_depth(0).data(),
              sizeof(float) * pixels);
  // With mapping, the new keyframe starts with the local maps where its sensor is blind, until
  // its own multi-view map replaces them.
  const bool with_local_maps = mapper_queue_ != nullptr;
  for (int i = 0; with_local_maps && i < KeyframeBuildTask::kLocalMaps; ++i) {
    LocalMap& m = building_->local_map(i);
    m.T_w_k = local_maps_[i].T_w_k;
    m.points.clear();
    for (const MapPoint& p : local_maps_[i].points) (void)m.points.push_back(p);
  }
  pending_keyframe_.reset_counter = reset_counter_;
  KeyframeOrder order;
  order.id = next_keyframe_id_++;
  order.timestamp_ns = pending_keyframe_.pose.timestamp_ns;
  order.T_w_k = pending_keyframe_.T_w_k;
  order.with_local_maps = with_local_maps;
  // With nothing to track against yet (the first keyframe, or the first in a loaded map), the
  // tracker has nothing else to do: it is built at once.
  building_->submit(order, reference_ == nullptr);
  adopt_built_keyframe();  // built already when synchronous or at once
}

void TrackingPipeline::adopt_built_keyframe() {
  if (!building_->built()) return;
  if (pending_keyframe_.reset_counter != reset_counter_) {
    // Its pose is from before the map moved (a restart, relocalisation or loop correction).
    ++counters_.keyframes_stale;
    building_->release();
    return;
  }
  Keyframe* kf = pool_->acquire(reference_);
  building_->hand_over(kf);
  reference_ = kf;
  fallback_ = nullptr;
  ++counters_.keyframes;
  offer_to_loop(*kf, pending_keyframe_.link, building_->frame());
  if (pending_keyframe_.to_mapper) {
    offer_to_mapper(pending_keyframe_.pose, building_->frame(), &building_->edges());
  }
  building_->release();
}

void TrackingPipeline::adopt_map(Keyframe* kf) {
  if (!pool_->adopt_map(kf)) return;
  LocalMap& m = local_maps_[next_local_map_];
  next_local_map_ = (next_local_map_ + 1) % 2;
  m.T_w_k = kf->T_w_k;
  m.points.clear();
  for (const MapPoint& p : kf->map_points) (void)m.points.push_back(p);
}

void TrackingPipeline::offer_to_mapper(const PoseEstimate& pose, const FramePyramid& f,
                                       const ImageU8* keyframe_edges) {
  if (mapper_queue_ == nullptr) return;
  const bool new_keyframe = keyframe_edges != nullptr;
  MapperFrame* slot = mapper_queue_->begin_push();
  if (slot == nullptr) {
    ++counters_.mapper_dropped_frames;
    if (new_keyframe) ++counters_.mapper_dropped_keyframes;
    return;
  }
  slot->sequence = pose.sequence;
  slot->reset_counter = pose.reset_counter;
  slot->timestamp_ns = pose.timestamp_ns;
  slot->T_w_c = pose.T_w_c;
  std::memcpy(slot->gray.data(), f.gray(0).data(), sizeof(float) * slot->gray.size());
  slot->new_keyframe = KeyframeHandle();
  if (new_keyframe) {
    std::memcpy(slot->inverse_depth.data(), f.inverse_depth(0).data(),
                sizeof(float) * slot->inverse_depth.size());
    std::memcpy(slot->edges.data(), keyframe_edges->data(), slot->edges.size());
    slot->new_keyframe = pool_->handle(reference_);
    pool_->pin(slot->new_keyframe);
  }
  mapper_queue_->publish();
}

}  // namespace rgbdtam

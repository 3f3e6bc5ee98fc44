#include "rgbdtam/runtime/tracking_pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace rgbdtam {

Status TrackingPipeline::init(const Params& params) {
  params_ = params;
  params_.tracker.inverse_depth_sigma = params.sensor.inverse_depth_sigma();
  undistorter_.init(params_.camera, params_.distortion);
  pyramid_.allocate(params_.camera, params_.sensor.depth_factor, params_.sensor.depth_range);
  propagated_.allocate(params_.camera, params_.sensor.depth_factor, params_.sensor.depth_range);
  depth_undistorted_.allocate(params_.camera.width_px, params_.camera.height_px);
  builder_.allocate(params_.camera, params_.tracker);
  const int map_points = params_.map_enabled ? params_.map_seeds : 0;
  pool_.allocate(params_.keyframe_pool_size, builder_, map_points);
  for (LocalMap& m : local_maps_) m.points.reserve_once(map_points);
  Keyframe model;
  builder_.allocate_keyframe(&model);
  tracker_.allocate(model, params_.tracker);
  return Status::ok();
}

SE3 TrackingPipeline::predict_pose() const {
  if (params_.tracker.motion_model && valid_history_ >= 2) {
    return T_w_last_ * (T_w_before_last_.inverse() * T_w_last_);
  }
  return T_w_last_;
}

bool TrackingPipeline::reuse_keyframe(const SE3& T_w_c, PoseEstimate* out) {
  // The earlier keyframes nearest to the camera, a radian of rotation counted as 0.3 m.
  constexpr int kMaxCandidates = 16;
  constexpr double kMetresPerRadian = 0.3;
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
    for (int i = 0; i < pool_.size(); ++i) {
      Keyframe* kf = &pool_.at(i);
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
  // Rank the candidates by their overlap at the current estimate; track only the best.
  Keyframe* best = nullptr;
  double best_overlap = params_.tracker.keyframe_overlap;
  for (int i = 0; i < count; ++i) {
    adopt_map(candidates[i]);
    const double overlap =
        tracker_.overlap_at(*candidates[i], pyramid_, candidates[i]->T_w_k.inverse() * T_w_c);
    if (overlap >= best_overlap) {
      best = candidates[i];
      best_overlap = overlap;
    }
  }
  if (best == nullptr) return false;
  const TrackResult best_result = tracker_.track(*best, pyramid_, best->T_w_k.inverse() * T_w_c);
  if (best_result.state != TrackingState::kOk ||
      best_result.overlap < params_.tracker.keyframe_overlap) {
    return false;
  }
  reference_ = best;
  out->T_w_c = best->T_w_k * best_result.T_k_c;
  out->keyframe_id = best->id;
  out->overlap = static_cast<float>(best_result.overlap);
  out->information = best_result.information;
  out->flags |= kKeyframeReused;
  T_w_last_ = out->T_w_c;
  ++counters_.reused;
  return true;
}

void TrackingPipeline::start_keyframe(const SensorFrame& frame, const SE3& T_w_c,
                                      PoseEstimate* out) {
  Keyframe* kf = pool_.acquire(reference_);
  // With mapping, the new keyframe starts with the previous one's map where its sensor is
  // blind (the authors' "local map"), until its own multi-view map replaces it.
  const bool propagate = mapper_queue_ != nullptr;
  if (propagate) propagate_map(T_w_c);
  builder_.build(pyramid_, next_keyframe_id_++, frame.timestamp_ns, T_w_c, kf,
                 propagate ? &propagated_ : nullptr);
  reference_ = kf;
  ++counters_.keyframes;
  out->flags |= kNewKeyframe;
  out->keyframe_id = kf->id;
}

PoseEstimate TrackingPipeline::process(const SensorFrame& frame) {
  PoseEstimate out;
  out.sequence = frame.sequence;
  out.timestamp_ns = frame.timestamp_ns;
  out.information.setZero();
  ++counters_.frames;
  RGBDTAM_ASSERT(
      frame.width_px == params_.camera.width_px && frame.height_px == params_.camera.height_px,
      "sensor frame size differs from the configured camera");
  undistorter_.undistort_gray(frame.gray, &pyramid_.gray(0));
  pyramid_.build_gray();
  if (frame.depth != nullptr) {
    undistorter_.undistort_depth(frame.depth, &depth_undistorted_);
    pyramid_.build_inverse_depth(depth_undistorted_);
  } else {
    pyramid_.clear_depth();
    out.flags |= kNoDepth;
    ++counters_.without_depth;
  }

  if (reference_ == nullptr) {
    if (!pyramid_.has_depth()) {
      out.flags |= kNotInitialised;
      return out;
    }
    start_keyframe(frame, SE3(), &out);
    T_w_last_ = SE3();
    valid_history_ = 1;
    out.T_w_c = SE3();
    out.flags |= kPoseValid;
    out.overlap = 1.f;
    out.reset_counter = reset_counter_;
    ++counters_.tracked;
    offer_to_mapper(out, true);
    return out;
  }

  adopt_map(reference_);
  const SE3 T_w_guess = predict_pose();
  const TrackResult r =
      tracker_.track(*reference_, pyramid_, reference_->T_w_k.inverse() * T_w_guess);
  out.keyframe_id = reference_->id;
  out.overlap = static_cast<float>(r.overlap);
  out.photometric_sigma = static_cast<float>(r.photometric_sigma);
  out.residuals_used = r.residuals_used;
  out.iterations = r.iterations;
  out.information = r.information;
  const bool sigma_jumped =
      typical_photometric_sigma_ > 0.f && r.photometric_sigma > 0.0 &&
      r.photometric_sigma > params_.lost_sigma_ratio * typical_photometric_sigma_;
  if (r.state == TrackingState::kOk && !sigma_jumped) {
    if (r.photometric_sigma > 0.0) {
      // A slow average: right after a new keyframe the scale is briefly tiny.
      const float sigma = static_cast<float>(r.photometric_sigma);
      typical_photometric_sigma_ = typical_photometric_sigma_ == 0.f
                                       ? sigma
                                       : 0.95f * typical_photometric_sigma_ + 0.05f * sigma;
    }
    out.T_w_c = reference_->T_w_k * r.T_k_c;
    out.flags |= kPoseValid;
    ++counters_.tracked;
    consecutive_lost_ = 0;
    T_w_before_last_ = T_w_last_;
    T_w_last_ = out.T_w_c;
    valid_history_ = valid_history_ < 2 ? valid_history_ + 1 : 2;
    if (r.overlap < params_.tracker.keyframe_overlap && !reuse_keyframe(out.T_w_c, &out) &&
        pyramid_.has_depth()) {
      start_keyframe(frame, out.T_w_c, &out);
    }
  } else {
    out.flags |= kLost;
    ++counters_.lost;
    valid_history_ = valid_history_ > 0 ? 1 : 0;  // the velocity is no longer trusted
    if (++consecutive_lost_ >= params_.lost_frames_before_reset && pyramid_.has_depth()) {
      // Restart from the last good pose: the estimate jumps, so say so.
      start_keyframe(frame, T_w_last_, &out);
      ++reset_counter_;
      ++counters_.resets;
      out.flags |= kReset;
      consecutive_lost_ = 0;
    }
  }
  out.reset_counter = reset_counter_;
  if ((out.flags & kPoseValid) != 0) offer_to_mapper(out, (out.flags & kNewKeyframe) != 0);
  return out;
}

void TrackingPipeline::adopt_map(Keyframe* kf) {
  if (!kf->adopt_map()) return;
  LocalMap& m = local_maps_[next_local_map_];
  next_local_map_ = (next_local_map_ + 1) % 2;
  m.T_w_k = kf->T_w_k;
  m.points.clear();
  for (const MapPoint& p : kf->map_points) (void)m.points.push_back(p);
}

void TrackingPipeline::propagate_map(const SE3& T_w_c) {
  ImageF& map = propagated_.inverse_depth_level0();
  const ImageF& sensor = pyramid_.inverse_depth(0);
  std::memcpy(map.data(), sensor.data(), sizeof(float) * static_cast<size_t>(map.size()));
  const PinholeIntrinsics& k = pyramid_.intrinsics(0);
  for (const LocalMap& local : local_maps_) {
    const SE3 T_c_k = T_w_c.inverse() * local.T_w_k;
    for (const MapPoint& p : local.points) {
      const Vector3d q = T_c_k * Vector3d(p.x, p.y, p.z);
      if (q.z() < 0.05) continue;
      const long u = std::lround(k.fx_px * q.x() / q.z() + k.cx_px);
      const long v = std::lround(k.fy_px * q.y() / q.z() + k.cy_px);
      if (u < 0 || v < 0 || u >= map.width() || v >= map.height()) continue;
      if (sensor.at(u, v) > 0.f) continue;  // the sensor's own reading wins
      map.at(u, v) = std::max(map.at(u, v), static_cast<float>(1.0 / q.z()));  // nearest wins
    }
  }
  propagated_.build_inverse_depth_levels();
}

void TrackingPipeline::offer_to_mapper(const PoseEstimate& pose, bool new_keyframe) {
  if (mapper_queue_ == nullptr) return;
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
  std::memcpy(slot->gray.data(), pyramid_.gray(0).data(), sizeof(float) * slot->gray.size());
  slot->new_keyframe = nullptr;
  if (new_keyframe) {
    std::memcpy(slot->inverse_depth.data(), pyramid_.inverse_depth(0).data(),
                sizeof(float) * slot->inverse_depth.size());
    std::memcpy(slot->edges.data(), builder_.edges().data(), slot->edges.size());
    reference_->being_mapped.store(true, std::memory_order_release);
    slot->new_keyframe = reference_;
  }
  mapper_queue_->publish();
}

}  // namespace rgbdtam

#include "rgbdtam/runtime/tracking_pipeline.hpp"

namespace rgbdtam {

Status TrackingPipeline::init(const Params& params) {
  params_ = params;
  params_.tracker.inverse_depth_sigma = params.sensor.inverse_depth_sigma();
  undistorter_.init(params_.camera, params_.distortion);
  pyramid_.allocate(params_.camera);
  depth_undistorted_.allocate(params_.camera.width_px, params_.camera.height_px);
  builder_.allocate(params_.camera, params_.tracker);
  pool_.allocate(params_.keyframe_pool_size, builder_);
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

void TrackingPipeline::start_keyframe(const SensorFrame& frame, const SE3& T_w_c,
                                      PoseEstimate* out) {
  Keyframe* kf = pool_.acquire(reference_);
  builder_.build(pyramid_, next_keyframe_id_++, frame.timestamp_ns, T_w_c, kf);
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
  RGBDTAM_ASSERT(frame.width_px == params_.camera.width_px &&
                     frame.height_px == params_.camera.height_px,
                 "sensor frame size differs from the configured camera");
  undistorter_.undistort_gray(frame.gray, &pyramid_.gray(0));
  pyramid_.build_gray();
  if (frame.depth != nullptr) {
    undistorter_.undistort_depth(frame.depth, &depth_undistorted_);
    pyramid_.build_inverse_depth(depth_undistorted_, params_.sensor.depth_factor,
                                 params_.sensor.depth_range);
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
    return out;
  }

  const SE3 T_w_guess = predict_pose();
  const TrackResult r =
      tracker_.track(*reference_, pyramid_, reference_->T_w_k.inverse() * T_w_guess);
  out.keyframe_id = reference_->id;
  out.overlap = static_cast<float>(r.overlap);
  out.photometric_sigma = static_cast<float>(r.photometric_sigma);
  out.residuals_used = r.residuals_used;
  out.iterations = r.iterations;
  out.information = r.information;
  if (r.state == TrackingState::kOk) {
    out.T_w_c = reference_->T_w_k * r.T_k_c;
    out.flags |= kPoseValid;
    ++counters_.tracked;
    consecutive_lost_ = 0;
    T_w_before_last_ = T_w_last_;
    T_w_last_ = out.T_w_c;
    valid_history_ = valid_history_ < 2 ? valid_history_ + 1 : 2;
    if (r.overlap < params_.tracker.keyframe_overlap && pyramid_.has_depth()) {
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
  return out;
}

}  // namespace rgbdtam

#include "rgbdtam/runtime/tracking_pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace rgbdtam {
namespace {
// Initial guesses of the wider basin: the prediction turned about each camera axis in steps of
// 4 degrees, as far as the rotation-rate limit allows since the last valid pose. The coarsest
// level (80x60) converges from about 2-3 of its pixels, some 2.5 degrees at a 525 px focal
// length, so 4-degree steps leave no gap.
constexpr double kGuessTurnStepRad = 4.0 * M_PI / 180.0;
constexpr int kMaxGuessTurns = 4;  // 16 degrees: 480 deg/s over one 30 Hz frame
constexpr int kMaxGuesses = 5 + 6 * kMaxGuessTurns;
// A prior and the image agree when they differ by less than this many of the prior's standard
// deviations (the image's own rotation error, some 0.05 degrees, is small beside it).
constexpr double kPriorGateSigmas = 3.0;
// A velocity estimated across a longer gap (a loss, dropped frames) is not a velocity.
constexpr int64_t kMaxVelocityGapNs = 200'000'000;
}  // namespace

Status TrackingPipeline::init(const Params& params, KeyframePool* keyframes,
                              KeyframeBuildTask* building, ClockFn clock) {
  params_ = params;
  pool_ = keyframes;
  building_ = building;
  params_.tracker = tracking_options(params);
  params_.health = health_limits(params);
  undistorter_.init(params_.camera, params_.distortion);
  for (FramePyramid& f : frames_) {
    f.allocate(params_.camera, params_.sensor.depth_factor, params_.sensor.depth_range);
  }
  builder_.allocate(params_.camera, params_.tracker);
  const int map_points = params_.map_enabled ? params_.map_seeds : 0;
  pool_->allocate(params_.keyframe_pool_size, builder_, map_points);
  building_->allocate(params_, map_points, clock);
  for (LocalMap& m : local_maps_) m.points.reserve_once(map_points);
  Keyframe model;
  builder_.allocate_keyframe(&model);
  tracker_.allocate(model, params_.tracker);
  return Status::ok();
}

SE3 TrackingPipeline::predict_pose(int64_t t_ns) const {
  return T_w_last_ * SE3::exp(velocity_ * (static_cast<double>(t_ns - last_ns_) * 1e-9));
}

uint32_t TrackingPipeline::failed_checks(const TrackResult& r, Keyframe* kf, int64_t t_ns) {
  HealthContext context;
  context.typical_sigma = typical_.photometric[0];
  if (has_last_ && t_ns > last_ns_) {
    context.T_last_current = T_w_last_.inverse() * (kf->T_w_k * r.T_k_c);
    context.dt_s = static_cast<double>(t_ns - last_ns_) * 1e-9;
  }
  uint32_t failed = failed_health_checks(r, context, params_.health);
  // From an uncertain guess (after a loss) the planes of a plain scene can fit another place
  // too: the same test, along the direction the depth determines worst.
  const bool uncertain_guess = !previous_valid_;
  if (failed == 0 && (r.depth_degenerate || uncertain_guess) &&
      !unique_along_weak_direction(r, kf)) {
    failed |= kWeakDirection;
  }
  return failed;
}

bool TrackingPipeline::unique_along_weak_direction(const TrackResult& r, Keyframe* kf) {
  // A direction the depth leaves free rests on the image alone, and a texture-poor image can
  // hold several minima along it within one frame's motion (doors along a corridor). The pose
  // stands only if tracking from starts half a frame's largest motion to either side along that
  // direction comes back to it.
  constexpr double kFramePeriodS = 1.0 / 30.0;
  constexpr double kSameM = 0.02, kSameRad = 1.0 * M_PI / 180.0;
  const double step_m = 0.5 * params_.health.max_speed_m_s * kFramePeriodS;
  for (const double sign : {-1.0, 1.0}) {
    const SE3 start = r.T_k_c * SE3::exp(r.weak_direction * (sign * step_m));
    const TrackResult other = tracker_.track(*kf, frame(), start, typical_, r.terms);
    const SE3 d = r.T_k_c.inverse() * other.T_k_c;
    if (!(d.translation().norm() <= kSameM && so3_log(d.quaternion()).norm() <= kSameRad)) {
      return false;
    }
  }
  return true;
}

TrackingPipeline::Attempt TrackingPipeline::track_against(Keyframe* kf, const SE3& T_w_guess,
                                                          int64_t t_ns) {
  Attempt a;
  a.kf = kf;
  a.r = tracker_.track(*kf, frame(), kf->T_w_k.inverse() * T_w_guess, typical_);
  a.failed = failed_checks(a.r, kf, t_ns);
  return a;
}

bool TrackingPipeline::prior_applies(int64_t t_ns) const {
  return prior_.valid && has_last_ && prior_.from_ns == last_ns_ && prior_.to_ns == t_ns;
}

SE3 TrackingPipeline::turned_by_prior(const SE3& predicted) const {
  return SE3(T_w_last_.quaternion() * prior_.q_c0_c1, predicted.translation());
}

TrackingPipeline::Attempt TrackingPipeline::track_first(int64_t t_ns) {
  const SE3 predicted = predict_pose(t_ns);
  if (prior_applies(t_ns) && previous_valid_) {
    Attempt a = track_against(reference_, turned_by_prior(predicted), t_ns);
    const double disagreement =
        angle_between(prior_.q_c0_c1, T_w_last_.quaternion().conjugate() * a.T_w_c().quaternion());
    if (a.failed == 0 && disagreement <= kPriorGateSigmas * prior_.sigma_rad) {
      ++counters_.prior_used;
      return a;
    }
    // Never forced: the frame is tracked as without it, and no later guess uses it.
    ++counters_.prior_rejected;
    prior_.valid = false;
  }
  return track_against(reference_, predicted, t_ns);
}

TrackingPipeline::Attempt TrackingPipeline::track_from_guesses(Keyframe* kf, int64_t t_ns) {
  const SE3 predicted = predict_pose(t_ns);
  SE3 guesses[kMaxGuesses];
  int n = 0;
  const SE3 T_k_w = kf->T_w_k.inverse();
  auto add = [&](const SE3& T_w_c) { guesses[n++] = T_k_w * T_w_c; };
  add(predicted);
  if (prior_applies(t_ns)) add(turned_by_prior(predicted));  // a turn faster than the basin
  add(T_w_last_);                                            // the camera stopped
  const double dt = static_cast<double>(t_ns - last_ns_) * 1e-9;
  add(T_w_last_ * SE3::exp(velocity_ * (0.5 * dt)));  // it slowed down ...
  add(T_w_last_ * SE3::exp(velocity_ * (2.0 * dt)));  // ... or sped up
  const double reach = params_.health.max_rotation_rate_rad_s * dt;
  const int turns =
      std::clamp(static_cast<int>(std::ceil(reach / kGuessTurnStepRad)), 1, kMaxGuessTurns);
  for (int step = 1; step <= turns; ++step) {
    const double turn = step * kGuessTurnStepRad;
    for (int axis = 0; axis < 3; ++axis) {
      for (const double sign : {-1.0, 1.0}) {
        add(predicted * SE3(so3_exp(Vector3d::Unit(axis) * (sign * turn)), Vector3d::Zero()));
      }
    }
  }
  Attempt a;
  a.kf = kf;
  a.r = tracker_.track_best(*kf, frame(), guesses, n, typical_);
  a.failed = failed_checks(a.r, kf, t_ns);
  return a;
}

TrackingPipeline::Attempt TrackingPipeline::without_misfit_term(const Attempt& a, int64_t t_ns) {
  // A term that does not fit while the other does (blur against a sharp keyframe, depth
  // misregistered or missing) is dropped and the pose solved from the other alone; it is valid
  // only if that term on its own determines the pose.
  const uint32_t misfit = a.failed & (kPhotometricMisfit | kGeometricMisfit);
  if (a.failed == 0 || a.r.terms != kAllTerms ||
      (misfit != kPhotometricMisfit && misfit != kGeometricMisfit)) {
    return a;
  }
  const uint8_t keep = misfit == kPhotometricMisfit ? kGeometricTerm : kPhotometricTerm;
  Attempt b;
  b.kf = a.kf;
  b.r = tracker_.track(*a.kf, frame(), a.r.T_k_c, typical_, keep);
  b.failed = failed_checks(b.r, a.kf, t_ns);
  if (b.failed == 0) ++counters_.single_term;
  return b.failed == 0 ? b : a;
}

void TrackingPipeline::accept(const Attempt& a, const SensorFrame& frame, PoseEstimate* out) {
  reference_ = a.kf;
  fallback_ = nullptr;
  lost_since_ns_ = -1;
  const TrackResult& r = a.r;
  out->T_w_c = a.T_w_c();
  out->keyframe_id = a.kf->id;
  out->overlap = static_cast<float>(r.overlap);
  out->photometric_sigma = static_cast<float>(r.photometric_sigma);
  out->residuals_used = r.residuals_used;
  out->iterations = r.iterations;
  out->information = r.information / params_.covariance_scale;
  out->flags |= kPoseValid;
  ++counters_.tracked;
  if ((r.terms & kPhotometricTerm) != 0) {
    for (int l = 0; l < kPyramidLevels; ++l) {
      float& typical = typical_.photometric[l];
      typical = typical == 0.f ? r.level_sigma[l] : 0.95f * typical + 0.05f * r.level_sigma[l];
    }
  }
  const int64_t gap = frame.timestamp_ns - last_ns_;
  velocity_.setZero();
  if (params_.tracker.motion_model && has_last_ && gap > 0 && gap <= kMaxVelocityGapNs) {
    velocity_ = (T_w_last_.inverse() * out->T_w_c).log() / (static_cast<double>(gap) * 1e-9);
  }
  T_w_last_ = out->T_w_c;
  last_ns_ = frame.timestamp_ns;
  has_last_ = true;
  // The paper's keyframe criterion (overlap) and the authors' (camera motion). As in the
  // authors' code, motion alone ends a keyframe only once its map is made: cut earlier, a far
  // scene loses the baseline its multi-view depth needs (synthetic wall at 6 m: 2-5 % depth
  // error instead of 0.2-0.9 %, and tracking on that map drifts).
  const bool moved = r.parallax > params_.tracker.keyframe_parallax && !pool_->pinned(a.kf);
  const bool new_view = r.overlap < params_.tracker.keyframe_overlap || moved;
  if (!building_->idle()) {
    ++counters_.frames_awaiting_keyframe;
  } else if (new_view && !reuse_keyframe(a, frame.timestamp_ns, out) && this->frame().has_depth()) {
    (void)ask_for_keyframe(out->T_w_c, odometry_link(out->T_w_c, out->information), true, out);
  }
}

void TrackingPipeline::on_lost(const SensorFrame& frame, uint32_t failed, PoseEstimate* out) {
  out->flags |= kLost;
  out->failed_checks = failed;
  ++counters_.lost;
  // Lost for the whole window, counted from the first lost frame: after an outage of the
  // sensor the frames that follow are relocalisation's chances, not lost time already spent.
  if (lost_since_ns_ < 0) lost_since_ns_ = frame.timestamp_ns;
  if (frame.timestamp_ns - lost_since_ns_ >= params_.reset_after_lost_ns &&
      this->frame().has_depth() && ask_for_keyframe(T_w_last_, restart_link(), false, out)) {
    // Restart from the last valid pose: the estimate jumps, so say so.
    fallback_ = nullptr;
    lost_since_ns_ = -1;
    last_ns_ = frame.timestamp_ns;
    velocity_.setZero();
    last_valid_frame_kept_ = false;
    ++reset_counter_;
    ++counters_.resets;
    out->flags |= kReset;
  }
}

PoseEstimate TrackingPipeline::process(const SensorFrame& frame) {
  build_pending_keyframe();  // in case the caller has not
  adopt_built_keyframe();
  const PoseEstimate out = track(frame);
  if (pending_keyframe_.due) pending_keyframe_.pose = out;
  return out;
}

PoseEstimate TrackingPipeline::track(const SensorFrame& frame) {
  PoseEstimate out;
  out.sequence = frame.sequence;
  out.timestamp_ns = frame.timestamp_ns;
  out.information.setZero();
  ++counters_.frames;
  RGBDTAM_ASSERT(
      frame.width_px == params_.camera.width_px && frame.height_px == params_.camera.height_px,
      "sensor frame size differs from the configured camera");
  FramePyramid& pyramid = this->frame();
  undistorter_.undistort_gray(frame.gray, &pyramid.gray(0));
  pyramid.build_gray();
  // A structured-light sensor measures surfaces: real frames have 95-98 % of their valid
  // depth on one (fr1_xyz, fr3_teddy), uniform noise 10 %. Depth that is mostly not a surface
  // would warp the photometric term to anywhere, so the frame counts as without depth.
  constexpr int kSurfaceStridePx = 4;
  constexpr double kMinSurfaceFraction = 0.5;
  bool depth_usable = false;
  if (frame.depth != nullptr) {
    pyramid.build_inverse_depth(frame.depth, undistorter_);
    const SurfaceCount c = count_surface_pixels(pyramid.inverse_depth(0), kSurfaceStridePx);
    depth_usable = c.on_surface >= kMinSurfaceFraction * c.valid;
    if (!depth_usable) ++counters_.depth_not_surface;
  }
  if (!depth_usable) {
    pyramid.clear_depth();
    out.flags |= kNoDepth;
    ++counters_.without_depth;
  }

  if (reference_ == nullptr) {
    // Waiting for the first keyframe too, when it is built on another thread.
    if (!pyramid.has_depth() || !building_->idle()) {
      out.flags |= kNotInitialised;
      return out;
    }
    if (localising_) {
      find_in_loaded_map(frame, &out);
      return out;
    }
    (void)ask_for_keyframe(SE3(), restart_link(), true, &out);
    T_w_last_ = SE3();
    last_ns_ = frame.timestamp_ns;
    has_last_ = true;
    out.T_w_c = SE3();
    out.flags |= kPoseValid;
    out.overlap = 1.f;
    out.reset_counter = reset_counter_;
    ++counters_.tracked;
    current_ = 1 - current_;
    last_valid_frame_kept_ = true;
    previous_valid_ = true;
    return out;
  }

  // Every finished map, not only the reference's: the local maps that fill a new keyframe's
  // sensor-blind pixels must be the newest, and the mapper may finish a keyframe after the
  // tracker has moved on from it.
  for (int i = 0; i < pool_->size(); ++i) adopt_map(&pool_->at(i));
  adopt_corrections();
  const int64_t t = frame.timestamp_ns;
  Attempt a = track_first(t);
  // One term alone only while tracking is continuous: from an uncertain guess (after a loss,
  // or from the wider basin) one term can fit the wrong place (planes slide along planes).
  if (previous_valid_) a = without_misfit_term(a, t);
  if (a.failed != 0) {
    ++counters_.retried;
    const uint32_t first_failure = a.failed;
    a = track_from_guesses(reference_, t);
    if (a.failed == 0) ++counters_.recovered_by_guesses;
    Keyframe* last = a.failed != 0 ? keyframe_from_last_valid_frame() : nullptr;
    if (last != nullptr) {
      const Attempt b = track_from_guesses(last, t);
      if (b.failed == 0) ++counters_.recovered_by_last_frame;
      if (b.failed == 0) a = b;
    }
    if (a.failed != 0) a.failed |= first_failure;
  }
  out.keyframe_id = reference_->id;
  if (a.failed == 0) {
    accept(a, frame, &out);
  } else if (!relocalise(frame, &out)) {
    on_lost(frame, a.failed, &out);
  }
  out.flags |= pending_flags_;
  pending_flags_ = 0;
  out.reset_counter = reset_counter_;
  const bool valid = (out.flags & kPoseValid) != 0;
  // A keyframe's frame goes to the mapper with the keyframe, once built.
  if (valid && !pending_keyframe_.due) offer_to_mapper(out, this->frame(), nullptr);
  if (valid && t <= withhold_until_ns_) {
    out.flags = (out.flags & ~kPoseValid) | kSettling;
    ++counters_.withheld;
  }
  if (valid) current_ = 1 - current_;  // keep this frame as the last valid one
  last_valid_frame_kept_ = last_valid_frame_kept_ || valid;
  previous_valid_ = valid;
  return out;
}

}  // namespace rgbdtam

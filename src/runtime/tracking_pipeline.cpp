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
constexpr int kMaxGuesses = 4 + 6 * kMaxGuessTurns;
// A velocity estimated across a longer gap (a loss, dropped frames) is not a velocity.
constexpr int64_t kMaxVelocityGapNs = 200'000'000;
}  // namespace

Status TrackingPipeline::init(const Params& params, KeyframePool* keyframes) {
  params_ = params;
  pool_ = keyframes;
  params_.tracker.inverse_depth_sigma = params.sensor.inverse_depth_sigma();
  params_.tracker.inverse_depth_sigma_floor = params.sensor.inverse_depth_quantum_sigma();
  undistorter_.init(params_.camera, params_.distortion);
  for (FramePyramid& f : frames_) {
    f.allocate(params_.camera, params_.sensor.depth_factor, params_.sensor.depth_range);
  }
  propagated_.allocate(params_.camera, params_.sensor.depth_factor, params_.sensor.depth_range);
  depth_undistorted_.allocate(params_.camera.width_px, params_.camera.height_px);
  builder_.allocate(params_.camera, params_.tracker);
  const int map_points = params_.map_enabled ? params_.map_seeds : 0;
  pool_->allocate(params_.keyframe_pool_size, builder_, map_points);
  for (LocalMap& m : local_maps_) m.points.reserve_once(map_points);
  Keyframe model;
  builder_.allocate_keyframe(&model);
  tracker_.allocate(model, params_.tracker);
  return Status::ok();
}

void TrackingPipeline::connect_loop(LoopQueue* keyframes, CorrectionQueue* corrections,
                                     PlaceStore* places, const Vocabulary* vocabulary) {
  loop_queue_ = keyframes;
  corrections_ = corrections;
  places_ = places;
  vocabulary_ = vocabulary;
  relocaliser_.allocate(params_);
  relocalisation_limits_.min_inliers = params_.loop.min_inliers;
  relocalisation_limits_.inverse_depth_sigma = params_.sensor.inverse_depth_sigma();
}

SE3 TrackingPipeline::predict_pose(int64_t t_ns) const {
  return T_w_last_ * SE3::exp(velocity_ * (static_cast<double>(t_ns - last_ns_) * 1e-9));
}

uint32_t TrackingPipeline::failed_checks(const TrackResult& r, const Keyframe& kf,
                                         int64_t t_ns) const {
  HealthContext context;
  context.typical_sigma = typical_.photometric[0];
  if (has_last_ && t_ns > last_ns_) {
    context.T_last_current = T_w_last_.inverse() * (kf.T_w_k * r.T_k_c);
    context.dt_s = static_cast<double>(t_ns - last_ns_) * 1e-9;
  }
  return failed_health_checks(r, context, params_.health);
}

TrackingPipeline::Attempt TrackingPipeline::track_against(Keyframe* kf, const SE3& T_w_guess,
                                                          int64_t t_ns) {
  Attempt a;
  a.kf = kf;
  a.r = tracker_.track(*kf, frame(), kf->T_w_k.inverse() * T_w_guess, typical_);
  a.failed = failed_checks(a.r, *kf, t_ns);
  return a;
}

TrackingPipeline::Attempt TrackingPipeline::track_from_guesses(Keyframe* kf, int64_t t_ns) {
  const SE3 predicted = predict_pose(t_ns);
  SE3 guesses[kMaxGuesses];
  int n = 0;
  const SE3 T_k_w = kf->T_w_k.inverse();
  auto add = [&](const SE3& T_w_c) { guesses[n++] = T_k_w * T_w_c; };
  add(predicted);
  add(T_w_last_);  // the camera stopped
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
  a.failed = failed_checks(a.r, *kf, t_ns);
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
  b.failed = failed_checks(b.r, *a.kf, t_ns);
  if (b.failed == 0) ++counters_.single_term;
  return b.failed == 0 ? b : a;
}

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

void TrackingPipeline::start_keyframe(const SensorFrame& frame, const SE3& T_w_c,
                                      PoseEstimate* out, bool after_reset) {
  const uint32_t reference_id = reference_ != nullptr ? reference_->id : next_keyframe_id_;
  Keyframe* kf = pool_->acquire(reference_);
  // With mapping, the new keyframe starts with the previous one's map where its sensor is
  // blind (the authors' "local map"), until its own multi-view map replaces it.
  const bool propagate = mapper_queue_ != nullptr;
  if (propagate) propagate_map(T_w_c);
  builder_.build(this->frame(), next_keyframe_id_++, frame.timestamp_ns, T_w_c, kf,
                 propagate ? &propagated_ : nullptr);
  reference_ = kf;
  ++counters_.keyframes;
  out->flags |= kNewKeyframe;
  out->keyframe_id = kf->id;
  offer_to_loop(*kf, reference_id, *out, after_reset);
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
    const int n = places_->database().query(relocaliser_.bow(), nullptr, nullptr, matches,
                                            kCandidates);
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
    // Its dense keyframe is gone: this frame becomes one, at the verified pose.
    start_keyframe(frame, T_w_c, out, true);
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
  if (c.poses.empty()) return;
  auto corrected = [&](uint32_t id) -> const KeyframePose* {
    const KeyframePose* p = std::lower_bound(
        c.poses.begin(), c.poses.end(), id,
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
    if (!have_newest || kf.id > newest_id) newest_delta = delta, newest_id = kf.id, have_newest = true;
    if (&kf == reference_) reference_delta = delta, have_reference = true;
    kf.T_w_k = p->T_w_k;
  }
  if (!have_newest) return;
  const uint32_t last_known = c.poses[c.poses.size() - 1].keyframe_id;
  for (int i = 0; i < pool_->size(); ++i) {
    Keyframe& kf = pool_->at(i);
    if (kf.id > last_known) kf.T_w_k = newest_delta * kf.T_w_k;
    if (&kf == reference_ && kf.id > last_known) reference_delta = newest_delta, have_reference = true;
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
  ++corrections_adopted_;
  ++reset_counter_;
  ++counters_.loop_corrections;
  pending_flags_ |= kLoopCorrected | kReset;
}

void TrackingPipeline::accept(const Attempt& a, const SensorFrame& frame, PoseEstimate* out) {
  reference_ = a.kf;
  fallback_ = nullptr;
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
  const bool moved = r.parallax > params_.tracker.keyframe_parallax &&
                     !pool_->pinned(a.kf);
  const bool new_view = r.overlap < params_.tracker.keyframe_overlap || moved;
  if (new_view && !reuse_keyframe(a, frame.timestamp_ns, out) && this->frame().has_depth()) {
    start_keyframe(frame, out->T_w_c, out);
  }
}

void TrackingPipeline::on_lost(const SensorFrame& frame, uint32_t failed, PoseEstimate* out) {
  out->flags |= kLost;
  out->failed_checks = failed;
  ++counters_.lost;
  if (frame.timestamp_ns - last_ns_ >= params_.reset_after_lost_ns && this->frame().has_depth()) {
    // Restart from the last valid pose: the estimate jumps, so say so.
    fallback_ = nullptr;
    start_keyframe(frame, T_w_last_, out, true);
    last_ns_ = frame.timestamp_ns;
    velocity_.setZero();
    last_valid_frame_kept_ = false;
    ++reset_counter_;
    ++counters_.resets;
    out->flags |= kReset;
  }
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
    undistorter_.undistort_depth(frame.depth, &depth_undistorted_);
    pyramid.build_inverse_depth(depth_undistorted_);
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
    if (!pyramid.has_depth()) {
      out.flags |= kNotInitialised;
      return out;
    }
    start_keyframe(frame, SE3(), &out);
    T_w_last_ = SE3();
    last_ns_ = frame.timestamp_ns;
    has_last_ = true;
    out.T_w_c = SE3();
    out.flags |= kPoseValid;
    out.overlap = 1.f;
    out.reset_counter = reset_counter_;
    ++counters_.tracked;
    offer_to_mapper(out, true);
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
  Attempt a = track_against(reference_, predict_pose(t), t);
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
  if (valid) offer_to_mapper(out, (out.flags & kNewKeyframe) != 0);
  if (valid && t <= withhold_until_ns_) {
    out.flags = (out.flags & ~kPoseValid) | kSettling;
    ++counters_.withheld;
  }
  if (valid) current_ = 1 - current_;  // keep this frame as the last valid one
  last_valid_frame_kept_ = last_valid_frame_kept_ || valid;
  previous_valid_ = valid;
  return out;
}

void TrackingPipeline::adopt_map(Keyframe* kf) {
  if (!pool_->adopt_map(kf)) return;
  LocalMap& m = local_maps_[next_local_map_];
  next_local_map_ = (next_local_map_ + 1) % 2;
  m.T_w_k = kf->T_w_k;
  m.points.clear();
  for (const MapPoint& p : kf->map_points) (void)m.points.push_back(p);
}

void TrackingPipeline::propagate_map(const SE3& T_w_c) {
  ImageF& map = propagated_.inverse_depth_level0();
  const ImageF& sensor = frame().inverse_depth(0);
  std::memcpy(map.data(), sensor.data(), sizeof(float) * static_cast<size_t>(map.size()));
  const PinholeIntrinsics& k = frame().intrinsics(0);
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
  std::memcpy(slot->gray.data(), frame().gray(0).data(), sizeof(float) * slot->gray.size());
  slot->new_keyframe = KeyframeHandle();
  if (new_keyframe) {
    std::memcpy(slot->inverse_depth.data(), frame().inverse_depth(0).data(),
                sizeof(float) * slot->inverse_depth.size());
    std::memcpy(slot->edges.data(), builder_.edges().data(), slot->edges.size());
    slot->new_keyframe = pool_->handle(reference_);
    pool_->pin(slot->new_keyframe);
  }
  mapper_queue_->publish();
}

}  // namespace rgbdtam

#include "rgbdtam/runtime/tracking_pipeline.hpp"

#include <algorithm>

#include "rgbdtam/core/pose_graph.hpp"

namespace rgbdtam {
namespace {

constexpr int kMaxReuseCandidates = 16;

// Where the camera was when the frame's depth was taken, in its colour image's frame: moved on
// at the current velocity from the colour's instant to the depth's (its stamp less the
// configured offset, the part of the stamps' difference that is not time between the images).
SE3 depth_camera(const SensorFrame& frame, const SensorModel& sensor, const MotionState& motion) {
  if (!sensor.depth_at_its_instant || frame.depth == nullptr || frame.depth_timestamp_ns == 0) {
    return SE3();
  }
  const int64_t dt_ns = frame.depth_timestamp_ns - sensor.depth_time_offset_ns - frame.timestamp_ns;
  return motion.motion_over(1e-9 * static_cast<double>(dt_ns));
}

// A rolling shutter's motion over each image's rows, at the current velocity.
void set_row_motions(const SensorModel& sensor, const MotionState& motion, FramePyramid* frame) {
  frame->set_row_motion(motion.twist_over(1e-9 * static_cast<double>(sensor.colour_readout_ns)));
  frame->set_depth_row_motion(
      motion.twist_over(1e-9 * static_cast<double>(sensor.depth_readout_ns)));
}

// While the frame is tracked on from the frame just before it, itself tracked on from its own (a
// velocity measured), each pyramid level places the rows by the motion from that frame's pose to
// the level's starting pose (Tracker). Across a lost frame the constant velocity is not known to
// hold, and after a restart or a relocalisation the last pose may be the wrong one: on rendered
// global-shutter scenes given a readout, rows following either let wrong poses out as valid.
void set_rows_follow_pose(const SensorModel& sensor, const MotionState& motion, int64_t t_ns,
                          FramePyramid* frame) {
  if (!motion.has_velocity() || !motion.previous_valid() || !motion.continuous_to(t_ns)) return;
  const double dt_s = motion.seconds_since_last(t_ns);
  frame->set_rows_follow_pose({motion.T_w_last().inverse(),
                               1e-9 * static_cast<double>(sensor.colour_readout_ns) / dt_s,
                               1e-9 * static_cast<double>(sensor.depth_readout_ns) / dt_s});
}

// Keyframes ranked by what they see of a frame, most first; of equals, the later added.
struct RankedKeyframes {
  Keyframe* keyframe[kMaxReuseCandidates];
  double visible[kMaxReuseCandidates];
  int count = 0;
  void add(Keyframe* kf, double seen) {
    int at = count++;
    for (; at > 0 && visible[at - 1] <= seen; --at) {
      keyframe[at] = keyframe[at - 1];
      visible[at] = visible[at - 1];
    }
    keyframe[at] = kf;
    visible[at] = seen;
  }
};

}  // namespace

Status TrackingPipeline::init(const Params& params, KeyframePool* keyframes,
                              KeyframeBuildTask* building, ClockFn clock) {
  params_ = params;
  params_.tracker = tracking_options(params);
  params_.health = health_limits(params);
  undistorter_.init(params_.camera, params_.distortion);
  depth_units_.init(params_.sensor);
  frames_.allocate(params_.camera, params_.sensor.depth_factor, params_.sensor.depth_range);
  motion_.init(params_.tracker.motion_model, params_.reset_after_lost_ns);
  blend_.init({params_.loop.blend_rate_m_per_s, params_.loop.blend_rate_rad_per_s,
               static_cast<double>(params_.loop.blend_within_ns) * 1e-9});
  keyframes_.init(params_, keyframes, building, clock);
  Keyframe model;
  keyframes_.allocate_model(&model);
  search_.allocate(model, params_.tracker, params_.health, alias_range_m(params_));
  return Status::ok();
}

void TrackingPipeline::start_in_loaded_map(uint32_t next_keyframe_id) {
  RGBDTAM_ASSERT(loop_.has_places() && counters_.frames == 0, "a map is loaded before tracking");
  keyframes_.start_at(next_keyframe_id);
  localising_ = true;
}

PoseEstimate TrackingPipeline::process(const SensorFrame& frame) {
  build_pending_keyframe();  // in case the caller has not
  adopt_built_keyframe();
  PoseEstimate out = begin_output(frame);
  const uint32_t sensor_failed = prepare(frame, &out);
  if (keyframes_.reference() == nullptr) {
    if (sensor_failed != 0) {
      // Nothing to start from, and the operator is told why.
      out.flags |= kNotInitialised | kLost;
      out.failed_checks = sensor_failed;
      ++counters_.lost;
    } else {
      start(frame, &out);
    }
  } else {
    keyframes_.adopt_all_maps();
    adopt_corrections();
    out.keyframe_id = keyframes_.reference()->id;
    if (sensor_failed != 0) {
      on_lost(frame, sensor_failed, &out);  // the sensor, not the scene: nothing to search
    } else {
      set_rows_follow_pose(params_.sensor, motion_, frame.timestamp_ns, &frames_.current());
      const Attempt a = estimate(frame.timestamp_ns);
      // From here on the rows are fixed: the pose found set them (accept), and a pose against
      // another part of the map (a keyframe reused, a relocalisation) differs from the last
      // frame's by that part's drift or a jump, not by the camera's motion.
      frames_.current().set_rows_fixed();
      // A frame lost because the scene repeats or leaves a direction free is no better found
      // by its appearance: the loss ends in a restart, not a relocalisation.
      const bool look_alike_scene = (a.failed & (kAmbiguous | kWeakDirection)) != 0;
      if (a.failed == 0) {
        accept(a, frame, &out, true);
      } else if (look_alike_scene || !relocalise(frame, &out)) {
        on_lost(frame, a.failed, &out);
      }
    }
    report(frame.timestamp_ns, &out);
  }
  if (keyframes_.due()) keyframes_.set_due_pose(out);
  send(&out);
  return out;
}

void TrackingPipeline::build_pending_keyframe() {
  if (!keyframes_.due()) return;
  keyframes_.order_pending(frames_, motion_.map_frame());
  adopt_built_keyframe();  // built already when synchronous or at once
}

PoseEstimate TrackingPipeline::begin_output(const SensorFrame& frame) {
  PoseEstimate out;
  out.sequence = frame.sequence;
  out.timestamp_ns = frame.timestamp_ns;
  out.information.setZero();
  ++counters_.frames;
  return out;
}

uint32_t TrackingPipeline::prepare(const SensorFrame& frame, PoseEstimate* out) {
  RGBDTAM_ASSERT(
      frame.width_px == params_.camera.width_px && frame.height_px == params_.camera.height_px,
      "sensor frame size differs from the configured camera");
  RGBDTAM_ASSERT(frame.depth_width_px == frame.width_px && frame.depth_height_px == frame.height_px,
                 "depth not in the colour camera: registration (DepthInColour) skipped");
  FramePyramid& pyramid = frames_.current();
  undistorter_.undistort_gray(frame.gray, &pyramid.gray(0));
  pyramid.set_T_c_d(depth_camera(frame, params_.sensor, motion_));
  set_row_motions(params_.sensor, motion_, &pyramid);
  pyramid.build_gray();
  // A structured-light sensor measures surfaces: real frames have 95-98 % of their valid
  // depth on one (fr1_xyz, fr3_teddy), uniform noise 10 %. Depth that is mostly not a surface
  // would warp the photometric term to anywhere, so the frame counts as without depth.
  constexpr int kSurfaceStridePx = 4;
  constexpr double kMinSurfaceFraction = 0.5;
  // Depth with no pixel in range (all 0, all saturated) is no depth either.
  bool depth_usable = false;
  uint32_t failed = 0;
  if (frame.depth != nullptr) {
    pyramid.build_inverse_depth(frame.depth, undistorter_);
    const SurfaceCount c = count_surface_pixels(pyramid.inverse_depth(0), kSurfaceStridePx);
    depth_usable = c.valid > 0 && c.on_surface >= kMinSurfaceFraction * c.valid;
    if (c.valid > 0 && !depth_usable) ++counters_.depth_not_surface;
    if (frozen_depth_.frozen(frame.depth, frame.depth_timestamp_ns, frame.gray,
                             frame.width_px * frame.height_px)) {
      failed |= kDepthFrozen;
      depth_usable = false;
      ++counters_.depth_frozen;
    }
    if (depth_units_.off(frame.depth, frame.width_px * frame.height_px)) {
      failed |= kDepthUnits;
      depth_usable = false;
      ++counters_.depth_units_off;
    }
  }
  if (!depth_usable) {
    pyramid.clear_depth();
    out->flags |= kNoDepth;
    ++counters_.without_depth;
  }
  return failed;
}

void TrackingPipeline::start(const SensorFrame& frame, PoseEstimate* out) {
  // Waiting for the first keyframe too, when it is built on another thread.
  if (!frames_.current().has_depth() || keyframes_.building()) {
    out->flags |= kNotInitialised;
    return;
  }
  if (localising_) {
    find_in_loaded_map(frame, out);
    return;
  }
  (void)keyframes_.ask(SE3(), keyframes_.restart_link(), true, frames_.current_slot(), out);
  motion_.begin(SE3(), frame.timestamp_ns);
  out->T_w_c = SE3();
  out->flags |= kPoseValid;
  out->overlap = 1.f;
  out->reset_counter = motion_.reset_counter();
  ++counters_.tracked;
  frames_.keep_current();
  motion_.end_frame(true);
}

void TrackingPipeline::adopt_built_keyframe() {
  const Keyframe* kf = keyframes_.adopt_built(motion_.map_frame());
  if (kf == nullptr) return;
  loop_.offer_keyframe(*kf, keyframes_.adopted_link(), keyframes_.adopted_window_links(),
                       keyframes_.adopted_frame());
  keyframes_.release_adopted();
}

void TrackingPipeline::adopt_corrections() {
  while (const LoopCorrection* c = loop_.next_correction()) {
    SE3 delta;
    if (keyframes_.move_by(*c, &delta)) {
      keyframes_.joined();
      SE3 sent_jump;
      if (blend_.absorb(delta, motion_.T_w_last(), &sent_jump)) {
        motion_.correct_blended(delta);
      } else {
        motion_.correct(delta, sent_jump, params_.loop.max_reported_jump_m,
                        params_.loop.max_reported_jump_rad);
      }
    }
    loop_.correction_taken();
  }
}

Attempt TrackingPipeline::estimate(int64_t t_ns) {
  Keyframe* reference = keyframes_.reference();
  const FramePyramid& frame = frames_.current();
  Attempt a = search_.first(reference, frame, motion_, &priors_, t_ns);
  // One term alone only while tracking is continuous: from an uncertain guess (after a loss,
  // or from the wider basin) one term can fit the wrong place (planes slide along planes).
  if (motion_.previous_valid()) a = search_.without_misfit_term(a, frame, motion_, t_ns);
  if (a.failed == 0) return a;
  ++counters_.retried;
  // Searched from any guess or reference, the reach stays as wide: relocalisation may tell.
  if ((a.failed & kBeyondSearch) != 0) return a;
  return recover(a, t_ns);
}

Attempt TrackingPipeline::recover(const Attempt& first, int64_t t_ns) {
  Keyframe* reference = keyframes_.reference();
  const FramePyramid& frame = frames_.current();
  // A reference taken up again may fit this view worse than the keyframe it replaced, which
  // fitted the frames until then: the predicted pose is tracked against that keyframe before
  // any wider search, one search rather than the wider one's tens (on a Pi 4, a frame in time
  // rather than two missed deadlines).
  if (Keyframe* left = keyframes_.left()) {
    const Attempt c = search_.track(left, frame, motion_.predict(t_ns), motion_, t_ns);
    if (c.failed == 0) {
      ++counters_.recovered_by_left_keyframe;
      return c;
    }
  }
  // Two minima within reach that fit the reference about as well: a wider search against it
  // can add minima, not remove those. The last valid frame, a second reference, may tell.
  Attempt a = first;
  if ((first.failed & kAmbiguous) == 0) {
    a = search_.from_guesses(reference, frame, motion_, priors_, t_ns);
    if (a.failed == 0) {
      ++counters_.recovered_by_guesses;
      return a;
    }
  }
  Keyframe* last = keyframes_.from_last_valid_frame(frames_, motion_.T_w_last(), motion_.last_ns());
  if (last != nullptr) {
    const Attempt b = search_.from_guesses(last, frame, motion_, priors_, t_ns);
    if (b.failed == 0) {
      ++counters_.recovered_by_last_frame;
      return b;
    }
  }
  a.failed |= first.failed;
  return a;
}

void TrackingPipeline::accept(const Attempt& a, const SensorFrame& frame, PoseEstimate* out,
                              bool continuous) {
  keyframes_.track_against(a.kf);
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
  search_.learn_scales(r);
  motion_.track(out->T_w_c, frame.timestamp_ns, continuous);
  // A keyframe made of this frame takes its rolling shutter from the motion just measured.
  set_row_motions(params_.sensor, motion_, &frames_.current());
  // The paper's keyframe criterion (overlap) and the authors' (camera motion). As in the
  // authors' code, motion alone ends a keyframe only once its map is made: cut earlier, a far
  // scene loses the baseline its multi-view depth needs (synthetic wall at 6 m: 2-5 % depth
  // error instead of 0.2-0.9 %, and tracking on that map drifts).
  const bool moved = r.parallax > params_.tracker.keyframe_parallax && !keyframes_.pinned(a.kf);
  const bool new_view = r.overlap < params_.tracker.keyframe_overlap || moved;
  if (keyframes_.building()) {
    keyframes_.count_frame_awaiting();
  } else if (new_view) {
    KeyframeLink window;
    WindowRequest window_later;
    if (!reuse_keyframe(a, frame.timestamp_ns, out, &window, &window_later) &&
        frames_.current().has_depth()) {
      (void)keyframes_.ask(out->T_w_c, keyframes_.odometry_link(out->T_w_c, out->information), true,
                           frames_.current_slot(), out, window, window_later);
    }
  }
}

bool TrackingPipeline::reuse_keyframe(const Attempt& current, int64_t t_ns, PoseEstimate* out,
                                      KeyframeLink* window, WindowRequest* window_later) {
  // The earlier keyframes nearest to the camera, ranked by what they see of this frame at the
  // current estimate; the best of map.reuse_candidates is tracked. For the local window, those
  // that see half of the frame, as two views must to show one place (shows_same_place), are
  // tracked too.
  constexpr double kWindowVisible = 0.5;
  const SE3 T_w_c = current.T_w_c();
  const double overlap = params_.tracker.keyframe_overlap;
  const bool window_on = params_.loop.window && loop_.has_places();
  const int wanted =
      std::max(params_.reuse_candidates, window_on ? params_.loop.window_keyframes : 0);
  Keyframe* candidates[kMaxReuseCandidates];
  const int count = keyframes_.nearest(T_w_c, std::min(wanted, kMaxReuseCandidates), candidates);
  Keyframe* best = nullptr;
  double best_visible = window_on ? std::min(kWindowVisible, overlap) : overlap;
  RankedKeyframes in_window;  // of equals, the later first, as the best
  for (int i = 0; i < count; ++i) {
    keyframes_.adopt_map(candidates[i]);
    const double visible = search_.visible_at(*candidates[i], frames_.current(),
                                              candidates[i]->T_w_k.inverse() * T_w_c);
    if (i < params_.reuse_candidates && visible >= best_visible) {
      best = candidates[i];
      best_visible = visible;
    }
    if (window_on && visible >= kWindowVisible) in_window.add(candidates[i], visible);
  }
  // The local window's measurements the keyframe builder's thread makes, off this core: all
  // but the best's when the best is tracked here.
  const bool best_tracked_here = best != nullptr && best_visible >= overlap;
  *window_later = {{}, 0, T_w_c, motion_, search_.typical_scales(), t_ns};
  const int later_wanted = params_.loop.window_keyframes - (best_tracked_here ? 1 : 0);
  for (int i = 0; i < in_window.count && window_later->count < later_wanted; ++i) {
    if (!best_tracked_here || in_window.keyframe[i] != best) {
      window_later->references[window_later->count++] = in_window.keyframe[i];
    }
  }
  if (!best_tracked_here) return false;  // none, or too little of the frame in view for reuse
  // Reused when it tracks the frame healthily, sees enough of it and has not moved too far.
  // As the authors' test (points in view, a lenient photometric bound), it does not ask for
  // the appearance the last keyframe had: an older keyframe looks less like the frame, which
  // is the price of its smaller drift (asking for the overlap too left 89 keyframes instead of
  // about 30 on fr1_xyz, and 1.15 cm all-frames ATE).
  const Attempt reused = search_.track(best, frames_.current(), T_w_c, motion_, t_ns);
  if (reused.failed != 0 || reused.r.visible < overlap ||
      reused.r.parallax > params_.tracker.keyframe_parallax) {
    // Not taken up: the new keyframe is measured against it too, as against its reference (and
    // against the window's others on the builder's thread).
    if (reused.failed == 0 && window_on) {
      window->reference_id = best->id;
      window->kind = EdgeKind::kCovisible;
      window->T_reference_keyframe = reused.r.T_k_c;
      window->information = graph_information(reused.r.information / params_.covariance_scale,
                                              window->T_reference_keyframe);
    }
    return false;
  }
  loop_.offer_reuse(current, reused, params_.covariance_scale);
  keyframes_.take_up(best);
  out->T_w_c = reused.T_w_c();
  out->keyframe_id = best->id;
  out->overlap = static_cast<float>(reused.r.overlap);
  out->information = reused.r.information / params_.covariance_scale;
  out->flags |= kKeyframeReused;
  motion_.remeasure(out->T_w_c);
  return true;
}

bool TrackingPipeline::relocalise(const SensorFrame& frame, PoseEstimate* out) {
  // A relocalised frame may become a keyframe: it waits until none is being built.
  if (!loop_.has_places() || !params_.loop.relocalise || !frames_.current().has_depth() ||
      keyframes_.building()) {
    return false;
  }
  const Relocalisation found =
      loop_.find(frames_.current(), motion_.has_last() ? &motion_.T_w_last() : nullptr);
  if (!found.found) return false;
  const SE3 T_w_c = found.T_w_c();
  // The camera must have been able to get there since the last valid pose: a frame that
  // shows another place for an instant (a glitch, a reflection) stays lost.
  const double dt = motion_.seconds_since_last(frame.timestamp_ns);
  if (motion_.has_last() && !(dt > 0.0 && within_motion_limits(motion_.T_w_last().inverse() * T_w_c,
                                                               dt, params_.health))) {
    return false;
  }
  const int64_t last_valid_ns = motion_.last_tracked_ns();
  Keyframe* kf = keyframes_.find(found.place_id);
  Attempt a;
  if (kf != nullptr) {
    // Refined at full resolution against the place's dense keyframe, where it still is.
    keyframes_.adopt_map(kf);
    a = search_.track(kf, frames_.current(), T_w_c, motion_, frame.timestamp_ns);
  } else {
    ++counters_.relocalised_past_the_pool;
  }
  if (a.failed == 0) {
    accept(a, frame, out, false);  // no velocity carries across a loss
  } else {
    // The frame becomes a keyframe at the verified pose, tied to the place by the alignment
    // where it measures the pose well enough for the map (else the loop module ties it).
    KeyframeLink link = keyframes_.restart_link();
    if (measures_pose(found.alignment)) {
      link.reference_id = found.place_id;
      link.kind = EdgeKind::kRelocalisation;
      link.T_reference_keyframe = found.alignment.T_a_b;
      link.information =
          graph_information(found.alignment.forward.information / params_.covariance_scale,
                            link.T_reference_keyframe);
    }
    keyframes_.forget_fallback();
    (void)keyframes_.ask(T_w_c, link, true, frames_.current_slot(), out);
    ++counters_.relocalised_on_new_keyframe;
    out->T_w_c = T_w_c;
    out->flags |= kPoseValid;
    motion_.begin(T_w_c, frame.timestamp_ns);
    // The keyframe's rows as the motion state knows it: no velocity across the loss.
    set_row_motions(params_.sensor, motion_, &frames_.current());
    ++counters_.tracked;
  }
  out->flags |= kRelocalised | kReset;
  keyframes_.joined();
  motion_.jumped(last_valid_ns);
  ++counters_.relocalised;
  return true;
}

void TrackingPipeline::find_in_loaded_map(const SensorFrame& frame, PoseEstimate* out) {
  // The map's world frame is the only one: until the camera is found in it, there is no pose
  // (a restart would begin a world frame of its own).
  if (!relocalise(frame, out)) {
    out->flags |= kLocalising;
    out->reset_counter = motion_.reset_counter();
    return;
  }
  localising_ = false;
  out->reset_counter = motion_.reset_counter();
  if (!keyframes_.due())
    keyframes_.offer_to_mapper(*out, motion_.map_frame(), frames_.current(), nullptr);
  frames_.keep_current();
  motion_.end_frame(true);
}

void TrackingPipeline::on_lost(const SensorFrame& frame, uint32_t failed, PoseEstimate* out) {
  out->flags |= kLost;
  out->failed_checks = failed;
  ++counters_.lost;
  if (motion_.lost_for_ns(frame.timestamp_ns) >= params_.reset_after_lost_ns &&
      frames_.current().has_depth() &&
      keyframes_.ask(motion_.T_w_last(), keyframes_.restart_link(), false, frames_.current_slot(),
                     out)) {
    // Restart from the last valid pose: the estimate jumps, so say so.
    keyframes_.forget_fallback();
    keyframes_.restarted();
    motion_.restart(frame.timestamp_ns);
    // The keyframe's rows as if still: the velocity from before the loss is half a second old.
    set_row_motions(params_.sensor, motion_, &frames_.current());
    frames_.forget_last_valid();
    out->flags |= kReset;
  }
}

void TrackingPipeline::report(int64_t t_ns, PoseEstimate* out) {
  const CorrectionJump correction = motion_.take_correction();
  out->flags |= correction.flags;
  out->reset_counter = motion_.reset_counter();
  const bool valid = (out->flags & kPoseValid) != 0;
  // A correction moved the pose by a jump nothing measured: its covariance covers the jump, for
  // a consumer that differences it with the last pose despite the reset counter.
  if (valid && correction.flags != 0) {
    out->information =
        information_with_jump(out->information, correction.translation_m, correction.rotation_rad);
  }
  // A keyframe's frame goes to the mapper with the keyframe, once built.
  if (valid && !keyframes_.due())
    keyframes_.offer_to_mapper(*out, motion_.map_frame(), frames_.current(), nullptr);
  if (valid && motion_.withheld(t_ns)) {
    out->flags = (out->flags & ~kPoseValid) | kSettling;
    ++counters_.withheld;
  }
  if (valid) frames_.keep_current();  // the last valid frame from now on
  motion_.end_frame(valid);
}

void TrackingPipeline::send(PoseEstimate* out) {
  out->T_w_c_map = out->T_w_c;
  if ((out->flags & kPoseValid) == 0) return;
  out->T_w_c = blend_.sent(out->T_w_c, out->timestamp_ns, out->reset_counter);
  if (!blend_.blending() && blend_.last_step_m() == 0.0 && blend_.last_step_rad() == 0.0) return;
  // The step towards the corrected map is motion the camera did not make: the covariance
  // covers it, for a consumer that differences the pose with the last one.
  out->flags |= kBlending;
  out->information =
      information_with_jump(out->information, blend_.last_step_m(), blend_.last_step_rad());
}

TrackingCounters TrackingPipeline::counters() const {
  TrackingCounters c;
  static_cast<StageCounters&>(c) = counters_;
  static_cast<MotionCounters&>(c) = motion_.counters();
  static_cast<PriorCounters&>(c) = priors_.counters();
  static_cast<SearchCounters&>(c) = search_.counters();
  static_cast<HandoverCounters&>(c) = keyframes_.counters();
  static_cast<LoopLinkCounters&>(c) = loop_.counters();
  return c;
}

}  // namespace rgbdtam

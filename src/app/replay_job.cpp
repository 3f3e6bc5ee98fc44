#include "replay_job.hpp"

#include <cmath>
#include <cstdio>

#include "config_files.hpp"
#include "json_line.hpp"
#include "memory_budget.hpp"
#include "rgbdtam/hal/atomic_file.hpp"
#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/runtime/pose_link.hpp"
#include "summary_lines.hpp"

namespace rgbdtam {
namespace {
// Past this many, problems are counted in the summary but not printed one by one.
constexpr int kMaxProblemsPrinted = 20;
constexpr int kProgressEvery = 100;

// Sized and touched at init, so that a replay's resident memory does not grow with its frames.
template <typename T>
void reserve_touched(std::vector<T>* v, size_t n, const T& fill) {
  v->assign(n, fill);
  v->clear();
}
}  // namespace

Status ReplayJob::init(const ReplayOptions& options) {
  options_ = options;
  const Params& p = options.params;
  RGBDTAM_RETURN_IF_ERROR(source_.open(options.sequence, sensor_image_size(p),
                                       p.sensor.max_rgb_depth_dt_ns,
                                       p.sensor.depth_time_offset_ns));
  if (source_.rgb_list().bad_lines > 0) {
    std::fprintf(stderr, "warning: %d unreadable lines in rgb.txt, skipped; first: %s\n",
                 source_.rgb_list().bad_lines, source_.rgb_list().first_problem.message());
  }
  if (source_.depth_list().bad_lines > 0) {
    std::fprintf(stderr, "warning: %d unreadable lines in depth.txt, skipped; first: %s\n",
                 source_.depth_list().bad_lines, source_.depth_list().first_problem.message());
  }
  // Outputs written at the end are checked now, not after the whole sequence.
  for (const char* at_end :
       {options.map_out_path, options.final_trajectory_path, options.trace_path}) {
    if (at_end != nullptr) RGBDTAM_RETURN_IF_ERROR(check_can_create(at_end));
  }
  const size_t per_frame = sizeof(StampedPose) + sizeof(Eigen::Matrix<double, 6, 6>);
  Status vocabulary_error;
  const bool loop = load_vocabulary(p, &vocabulary_, &vocabulary_error);
  RGBDTAM_RETURN_IF_ERROR(vocabulary_error);
  RGBDTAM_RETURN_IF_ERROR(check_memory_budget(p, loop ? vocabulary_.words() : 0, 0, per_frame,
                                              source_.frame_count(), memory_budget(0),
                                              &memory_needed_bytes_));
  RGBDTAM_RETURN_IF_ERROR(
      system_.init(p, monotonic_ns, options.map_sink, loop ? &vocabulary_ : nullptr));
  system_.set_loop_observer(options.loop_observer);
  if (options.map_in_path != nullptr) {
    const int64_t t0 = monotonic_ns();
    RGBDTAM_RETURN_IF_ERROR(load_map_file(options.map_in_path, p, &system_, &loaded_map_));
    map_load_ns_ = monotonic_ns() - t0;
  }
  RGBDTAM_RETURN_IF_ERROR(system_.start());
  if (options.trajectory_path != nullptr) {
    RGBDTAM_RETURN_IF_ERROR(writer_.open(options.trajectory_path));
  }
  if (options.covariance_path != nullptr) {
    RGBDTAM_RETURN_IF_ERROR(
        covariance_writer_.open(options.covariance_path, TrajectoryContent::kCovariance));
  }
  const size_t frames = static_cast<size_t>(source_.frame_count());
  reserve_touched(&estimates_, frames, StampedPose{0.0, SE3()});
  reserve_touched(&covariances_, frames, Eigen::Matrix<double, 6, 6>::Zero().eval());
  reserve_touched(&on_keyframes_, frames, OnKeyframe());
  reserve_touched(&final_estimates_, frames, StampedPose{0.0, SE3()});
  if (options.trace_path != nullptr) reserve_touched(&trace_, frames, TraceRow());
  started_ns_ = monotonic_ns();
  return Status::ok();
}

bool ReplayJob::step() {
  if (options_.max_frames > 0 && processed_ >= options_.max_frames) return false;
  if (stop_requested_.load() || !write_failure_.is_ok()) return false;
  const int64_t t0 = monotonic_ns();
  SensorFrame frame;
  Status warning;
  const Status s = source_.next(&frame, &warning);
  if (s.code() == StatusCode::kEndOfStream) return false;
  ++processed_;
  if (!s.is_ok() || !warning.is_ok()) {
    if (reported_problems_++ < kMaxProblemsPrinted) {
      std::fprintf(stderr, "%s: %s\n", s.is_ok() ? "warning" : "skipped frame",
                   s.is_ok() ? warning.message() : s.message());
    }
    if (!s.is_ok()) return true;
  }
  const int64_t waited_from = monotonic_ns();
  if (options_.paced) {
    if (first_frame_ns_ < 0) {
      first_frame_ns_ = waited_from;
      first_stamp_ns_ = frame.timestamp_ns;
    }
    sleep_until_ns(first_frame_ns_ + (frame.timestamp_ns - first_stamp_ns_));
  }
  const int64_t t1 = monotonic_ns();
  last_pose_ = system_.track(frame);
  const int64_t t2 = monotonic_ns();
  // The tracker's thread as in the firmware: tracking, and ordering and adopting keyframes; a
  // synchronous build is the builder's time, not the tracker's. (Threaded, the builder's
  // statistics are its thread's until it stops.)
  const bool synchronous = !options_.params.map_threaded;
  const LatencyStats& builds = system_.keyframe_building().time_per_keyframe();
  const int64_t builds_before = synchronous ? builds.count() : 0;
  system_.build_pending_keyframe();
  const bool built_here = synchronous && builds.count() > builds_before;
  const int64_t build_ns = built_here ? system_.keyframe_building().last_build_ns() : 0;
  const int64_t tracker_ns = monotonic_ns() - t1 - build_ns;
  tracker_thread_ms_.add(tracker_ns);
  system_.map_pending();
  if (options_.trace_path != nullptr) {
    trace_.push_back({frame.timestamp_ns, waited_from - t0, tracker_ns, build_ns, built_here,
                      system_.last_mapper_steps(), system_.last_loop_steps()});
  }
  write_failure_ = writer_.write(last_pose_);
  if (write_failure_.is_ok()) write_failure_ = covariance_writer_.write(last_pose_);
  const double t_s = static_cast<double>(last_pose_.timestamp_ns) * 1e-9;
  if ((last_pose_.flags & kPoseValid) != 0) {
    if (found_in_map_at_frame_ < 0 && loaded_map_.places > 0)
      found_in_map_at_frame_ = processed_ - 1;
    estimates_.push_back({t_s, last_pose_.T_w_c});
    covariances_.push_back(pose_covariance(last_pose_));
  }
  if ((last_pose_.flags & (kPoseValid | kSettling)) != 0) {
    SE3 T_w_k;
    const bool found = system_.keyframe_pose(last_pose_.keyframe_id, &T_w_k);
    on_keyframes_.push_back({t_s, last_pose_.keyframe_id, last_pose_.T_w_c,
                             T_w_k.inverse() * last_pose_.T_w_c_map, found});
  }
  const int64_t t3 = monotonic_ns();
  tracking_ms_.add(t2 - t1);
  frame_ms_.add(t3 - t0 - (t1 - waited_from));
  if (options_.progress && processed_ % kProgressEvery == 0) {
    std::fprintf(stderr, "[%5d/%d] tracking %.1f ms median, %u keyframes, %u lost\n", processed_,
                 source_.frame_count(), tracking_ms_.percentile_ms(0.5),
                 system_.tracking().counters().keyframes, system_.tracking().counters().lost);
  }
  return true;
}

Status ReplayJob::finish() {
  system_.finish();
  finished_ns_ = monotonic_ns();
  Status closed = writer_.close();
  if (closed.is_ok()) closed = covariance_writer_.close();
  final_estimates_.clear();
  for (const OnKeyframe& f : on_keyframes_) {
    SE3 T_w_k;
    const bool placed = f.on_keyframe && system_.keyframe_pose(f.keyframe_id, &T_w_k);
    // A keyframe the map forgot: the frame keeps the pose it was reported with.
    final_estimates_.push_back({f.t_s, placed ? T_w_k * f.T_k_c : f.T_w_c});
  }
  if (options_.map_out_path != nullptr && closed.is_ok() && system_.loop_enabled()) {
    const int64_t t0 = monotonic_ns();
    closed = save_map_file(options_.map_out_path, system_, options_.written_by);
    map_save_ns_ = closed.is_ok() ? monotonic_ns() - t0 : 0;
  }
  if (options_.trace_path != nullptr && closed.is_ok()) closed = write_trace();
  if (options_.final_trajectory_path != nullptr && closed.is_ok()) {
    TrajectoryWriter final_writer;
    closed = final_writer.open(options_.final_trajectory_path);
    for (const StampedPose& p : final_estimates_) {
      if (!closed.is_ok()) break;
      PoseEstimate e;
      e.timestamp_ns = static_cast<int64_t>(std::llround(p.stamp_s * 1e9));
      e.T_w_c = p.T_w_c;
      e.flags = kPoseValid;
      closed = final_writer.write(e);
    }
    if (closed.is_ok()) closed = final_writer.close();
  }
  return write_failure_.is_ok() ? closed : write_failure_;
}

Status ReplayJob::write_trace() const {
  AtomicFileWriter file;
  RGBDTAM_RETURN_IF_ERROR(file.init(options_.trace_path));
  RGBDTAM_RETURN_IF_ERROR(file.begin());
  // A failed write makes the later ones no-ops, and commit() names it.
  char line[160];
  int n = std::snprintf(line, sizeof(line),
                        "stamp_ns,sensor_ns,tracker_ns,keyframe,build_ns,mapper_items,mapper_ns,"
                        "loop_items,loop_ns\n");
  (void)file.write(line, static_cast<size_t>(n));
  for (const TraceRow& r : trace_) {
    n = std::snprintf(line, sizeof(line), "%lld,%lld,%lld,%d,%lld,%d,%lld,%d,%lld\n",
                      static_cast<long long>(r.stamp_ns), static_cast<long long>(r.sensor_ns),
                      static_cast<long long>(r.tracker_ns), r.keyframe ? 1 : 0,
                      static_cast<long long>(r.build_ns), r.mapper.items,
                      static_cast<long long>(r.mapper.ns), r.loop.items,
                      static_cast<long long>(r.loop.ns));
    (void)file.write(line, static_cast<size_t>(n));
  }
  return file.commit();
}

void ReplayJob::print_warnings() const { warn_about_depth(system_.tracking(), "rgbdtam replay"); }

void ReplayJob::print_summary() const {
  const TrackingCounters& c = system_.tracking().counters();
  const ReplayCounters& rc = source_.counters();
  const double seconds = static_cast<double>(finished_ns_ - started_ns_) * 1e-9;
  char residuals[16];
  options_.params.tracker.residuals.name(residuals, sizeof(residuals));
  std::printf("sequence: %s (%d frames listed), residuals %s\n", options_.sequence,
              source_.frame_count(), residuals);
  // Without depth: none delivered, or none usable (nothing in range, not a surface, frozen).
  std::printf("frames: read %u, skipped %u, without depth %u; tracked %u, lost %u, resets %u\n",
              rc.delivered, rc.skipped, c.without_depth, c.tracked, c.lost, c.resets);
  std::printf(
      "health: %u frames failed a first check (%u wider searches); %u recovered from other "
      "initial guesses, %u against the keyframe reuse had just left, %u against the last valid "
      "frame; %u tracked on one term (the other did not fit); %u depth frames set aside (not a "
      "surface), %u frozen (the last depth frame again)\n",
      c.retried, c.wider_searches, c.recovered_by_guesses, c.recovered_by_left_keyframe,
      c.recovered_by_last_frame, c.single_term, c.depth_not_surface, c.depth_frozen);
  std::printf("keyframes: %u created, %u reused, pool %d of %d, %d recycled\n", c.keyframes,
              c.reused, system_.tracking().keyframes().size(),
              system_.tracking().keyframes().capacity(), system_.tracking().keyframes().recycled());
  if (options_.params.map_enabled) {
    const MappingCounters& m = system_.mapper().counters();
    const double n = m.keyframes_mapped > 0 ? m.keyframes_mapped : 1;
    std::printf(
        "mapping: %u keyframes mapped (%s), %u frames triangulated, %u skipped to catch up, "
        "%u frames and %u keyframes dropped at the queue; per keyframe %.0f sensor, %.0f "
        "multi-view, %.0f fused edge points (the views %.0f %% of their information); mapper "
        "ms/keyframe median %.1f, p95 %.1f\n",
        m.keyframes_mapped, options_.params.map_threaded ? "own thread" : "synchronous",
        m.frames_observed, m.frames_skipped_late, c.mapper_dropped_frames,
        c.mapper_dropped_keyframes, m.points_sensor / n, m.points_multiview / n, m.points_fused / n,
        m.points_fused > 0 ? 100.0 * m.fused_multiview_share_sum / m.points_fused : 0.0,
        system_.mapper().time_per_keyframe().percentile_ms(0.5),
        system_.mapper().time_per_keyframe().percentile_ms(0.95));
  }
  print_loop_summary(system_);
  if (loaded_map_.places > 0) {
    std::printf("map file: %s, %u places and %u graph edges loaded in %.0f ms; ",
                options_.map_in_path, loaded_map_.places, loaded_map_.edges, map_load_ns_ * 1e-6);
    if (found_in_map_at_frame_ >= 0) {
      std::printf("found in it at frame %d\n", found_in_map_at_frame_);
    } else {
      std::printf("never found in it (no pose reported)\n");
    }
  }
  if (map_save_ns_ > 0) {
    std::printf("map file: %s, %d places saved in %.0f ms (written, synced and renamed)\n",
                options_.map_out_path, system_.places().size(), map_save_ns_ * 1e-6);
  }
  std::printf("memory: %.0f MB allocated at init (half of this machine's memory is the budget)\n",
              static_cast<double>(memory_needed_bytes_) / (1 << 20));
  std::printf("tracking ms/frame: median %.2f, p95 %.2f, max %.2f\n",
              tracking_ms_.percentile_ms(0.5), tracking_ms_.percentile_ms(0.95),
              tracking_ms_.max_ms());
  const LatencyStats& builds = system_.keyframe_building().time_per_keyframe();
  std::printf(
      "tracker thread ms/frame (tracking, keyframes ordered and adopted): median %.2f, p95 %.2f, "
      "max %.2f; keyframes built %s: median %.2f, p95 %.2f ms (%u tracked against the last one "
      "meanwhile, %u built stale)\n",
      tracker_thread_ms_.percentile_ms(0.5), tracker_thread_ms_.percentile_ms(0.95),
      tracker_thread_ms_.max_ms(),
      options_.params.map_threaded ? "on the builder's thread" : "synchronously",
      builds.percentile_ms(0.5), builds.percentile_ms(0.95),
      system_.tracking().counters().frames_awaiting_keyframe,
      system_.tracking().counters().keyframes_stale);
  std::printf(
      "whole frame ms (decode + tracking + output): median %.2f, p95 %.2f; %.1f fps "
      "overall\n",
      frame_ms_.percentile_ms(0.5), frame_ms_.percentile_ms(0.95),
      seconds > 0 ? static_cast<double>(processed_) / seconds : 0.0);
}

}  // namespace rgbdtam

namespace rgbdtam {

void ReplayJob::print_json(const EvaluationReport& r) const {
  const TrackingCounters& c = system_.tracking().counters();
  char residuals[16];
  options_.params.tracker.residuals.name(residuals, sizeof(residuals));
  JsonLine()
      .text("sequence", options_.sequence)
      .text("residuals", residuals)
      .integer("frames", c.frames)
      .integer("tracked", c.tracked)
      .integer("lost", c.lost)
      .integer("keyframes", c.keyframes)
      .integer("reused", c.reused)
      .number("track_median_ms", tracking_ms_.percentile_ms(0.5), 3)
      .number("track_p95_ms", tracking_ms_.percentile_ms(0.95), 3)
      .number("track_mean_ms", tracking_ms_.mean_ms(), 3)
      .number("tracker_thread_median_ms", tracker_thread_ms_.percentile_ms(0.5), 3)
      .number("tracker_thread_p95_ms", tracker_thread_ms_.percentile_ms(0.95), 3)
      .number("tracker_thread_max_ms", tracker_thread_ms_.max_ms(), 3)
      .number("keyframe_build_median_ms",
              system_.keyframe_building().time_per_keyframe().percentile_ms(0.5), 3)
      .number("keyframe_build_max_ms", system_.keyframe_building().time_per_keyframe().max_ms(), 3)
      .number("frame_median_ms", frame_ms_.percentile_ms(0.5), 3)
      .boolean("ate_ok", r.ate_ok)
      .number("ate_rmse_cm", r.ate.rmse_m * 100)
      .integer("poses_compared", r.ate.compared)
      .number("rpe_trans_cm_s", r.rpe.trans_rmse_m * 100)
      .number("rpe_rot_deg_s", r.rpe.rot_rmse_deg)
      .number("coverage", r.has_coverage ? r.coverage.fraction() : 0.0)
      .integer("false_valid", r.false_valid.count)
      .integer("false_valid_checked", r.false_valid.checked)
      .integer("resets", c.resets)
      .number("track_max_ms", tracking_ms_.max_ms(), 3)
      .integer("retried", c.retried)
      .integer("wider_searches", c.wider_searches)
      .integer("recovered_by_guesses", c.recovered_by_guesses)
      .integer("recovered_by_left_keyframe", c.recovered_by_left_keyframe)
      .integer("recovered_by_last_frame", c.recovered_by_last_frame)
      .integer("single_term", c.single_term)
      .integer("depth_not_surface", c.depth_not_surface)
      .integer("depth_frozen", c.depth_frozen)
      .integer("depth_units_off", c.depth_units_off)
      .number("nees_mean", r.nees.pairs > 0 ? r.nees.mean : NAN)
      .number("nees_median", r.nees.pairs > 0 ? r.nees.median : NAN)
      .number("nees_p99", r.nees.pairs > 0 ? r.nees.p99 : NAN)
      .integer("nees_pairs", r.nees.pairs)
      .integer("misleading", r.nees.misleading)
      .integer("ambiguous", c.ambiguous)
      .integer("beyond_search", c.beyond_search)
      .end();
}

}  // namespace rgbdtam

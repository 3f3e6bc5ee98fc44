#include "rgbdtam/runtime/firmware.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>

namespace rgbdtam {

Params FirmwareRuntime::system_params(const Params& params, const Board& board) {
  Params p = params;
  // Depth registered on the sensor's thread reaches the tracker as a registering device's does.
  if (board.sensor_registration_thread) p.depth_camera = DepthCameraParams();
  p.map_threaded = true;
  p.loop.threaded = true;
  return p;
}

Status FirmwareRuntime::init(const Params& params, const Board& board, ByteLink* link,
                             GpioOutputs* gpio, ClockFn clock, const Vocabulary* vocabulary) {
  RGBDTAM_RETURN_IF_ERROR(validate_board(board));
  params_ = system_params(params, board);
  RGBDTAM_RETURN_IF_ERROR(apply_board_capacity(board, &params_));
  board_ = board;
  clock_ = clock;
  gpio_ = gpio;
  period_ns_ = static_cast<int64_t>(1e9 / board.sensor_fps);
  RGBDTAM_RETURN_IF_ERROR(slam_.init(params_, clock, nullptr, vocabulary));
  PoseLinkConfig link_config;
  link_config.system_id = static_cast<uint8_t>(board.link_system_id);
  link_config.component_id = static_cast<uint8_t>(board.link_component_id);
  link_config.T_b_c = board.T_b_c;
  link_config.time_in_autopilot_clock = board.link_time_in_autopilot_clock;
  link_config.send_origin = !std::isnan(board.origin_latitude_deg);
  if (link_config.send_origin) {  // validated: both set, within range
    link_config.origin_latitude_e7 =
        static_cast<int32_t>(std::lround(board.origin_latitude_deg * 1e7));
    link_config.origin_longitude_e7 =
        static_cast<int32_t>(std::lround(board.origin_longitude_deg * 1e7));
    link_config.origin_altitude_mm = static_cast<int32_t>(
        std::lround(std::isnan(board.origin_altitude_m) ? 0.0 : board.origin_altitude_m * 1e3));
  }
  link_.init(link_config, link, kLinkQueueSlots, clock);
  attitude_.init(board.T_b_c, board.autopilot_attitude_sigma_rad);
  led_.init(gpio, board.gpio_led_line);
  if (board.obstacle_rate_hz > 0) {
    ObstacleOptions options;
    options.lowest_m = board.obstacle_lowest_m;
    options.highest_m = board.obstacle_highest_m;
    options.fov_deg = board.obstacle_fov_deg;
    obstacles_.init(params_.camera, board.T_b_c, params_.sensor.depth_factor,
                    params_.sensor.depth_range, options);
    blinded_.init(params_.health.max_speed_m_s);
    obstacle_period_ns_ = static_cast<int64_t>(1e9 / board.obstacle_rate_hz);
  }
  return Status::ok();
}

void FirmwareRuntime::report_obstacles(const SensorFrame& frame) {
  const int64_t stamp_ns =
      frame.depth_timestamp_ns != 0 ? frame.depth_timestamp_ns : frame.timestamp_ns;
  // Half a frame of slack, so that 10 Hz at 30 Hz is every third frame despite stamp jitter.
  const bool due = stamp_ns - last_obstacles_ns_ + period_ns_ / 2 >= obstacle_period_ns_ ||
                   stamp_ns < last_obstacles_ns_;  // a recording started again
  if (obstacle_period_ns_ == 0 || frame.depth == nullptr || !due) return;
  if (stamp_ns < last_obstacles_ns_) blinded_.forget();
  const double dt_s = static_cast<double>(stamp_ns - last_obstacles_ns_) * 1e-9;
  last_obstacles_ns_ = stamp_ns;
  ObstacleSectors sectors;
  obstacles_.measure(frame.depth, &sectors);
  blinded_.mark(dt_s, &sectors);
  if (link_.post_obstacles(sectors, stamp_ns)) ++counters_.obstacle_reports;
}

Status FirmwareRuntime::start() {
  RGBDTAM_RETURN_IF_ERROR(place_this_thread(board_.tracker, "rgbdtam-tracker"));
  RGBDTAM_RETURN_IF_ERROR(slam_.start(board_.mapper, board_.loop, board_.builder));
  RGBDTAM_RETURN_IF_ERROR(link_.start(board_.link));
  started_ = true;
  return Status::ok();
}

void FirmwareRuntime::post_event(uint8_t severity, const char* text) {
  if (link_.post_status(severity, text)) ++counters_.status_texts;
}

Status FirmwareRuntime::load_map(const uint8_t* data, size_t size, MapFileInfo* info) {
  RGBDTAM_RETURN_IF_ERROR(slam_.load_map(data, size, info));
  localising_ = true;
  return Status::ok();
}

PoseEstimate FirmwareRuntime::on_frame(const SensorFrame& frame, int64_t arrival_ns) {
  const int64_t t0 = clock_();
  const bool trigger = gpio_ != nullptr && board_.gpio_trigger_line >= 0;
  if (trigger) gpio_->set(board_.gpio_trigger_line, true);  // the next exposure starts now
  if (board_.autopilot_attitude) {
    link_.take_attitudes([this](const AttitudeSample& s) { attitude_.add(s); });
    const int64_t last_ns = slam_.tracking().last_tracked_ns();
    if (last_ns >= 0) slam_.set_rotation_prior(attitude_.prior(last_ns, frame.timestamp_ns));
  }
  const PoseEstimate pose = slam_.track(frame);
  attitude_.on_pose(pose);
  ++counters_.frames;
  const bool valid = (pose.flags & kPoseValid) != 0;
  if (valid) ++counters_.tracked;
  if ((pose.flags & kLost) != 0) ++counters_.lost;
  // Events on transitions only, so that a long loss is one message, not one per frame.
  if ((pose.flags & kLost) != 0 && !lost_) {
    lost_ = true;
    // The checks the pose failed tell the operator why.
    char reasons[160], text[kMaxStatusTextChars + 1];
    describe_health(pose.failed_checks, reasons, sizeof(reasons));
    std::snprintf(text, sizeof(text), "rgbdtam: lost: %s", reasons);
    post_event(mavlink::kMavSeverityWarning, text);
  } else if (valid && lost_) {
    lost_ = false;
    post_event(mavlink::kMavSeverityInfo, (pose.flags & kRelocalised) != 0
                                              ? "rgbdtam: relocalised in the map"
                                              : "rgbdtam: tracking regained");
  }
  if (localising_ && valid) {
    localising_ = false;
    post_event(mavlink::kMavSeverityInfo, "rgbdtam: found in the saved map, poses in its frame");
  }
  if ((pose.flags & kLoopCorrected) != 0) {
    post_event(mavlink::kMavSeverityInfo, "rgbdtam: loop closed, map corrected");
  }
  report_stores_full();
  (void)link_.post_pose(pose, arrival_ns, attitude_.levelled() ? &attitude_.q_l_w() : nullptr);
  report_obstacles(slam_.last_frame());  // needs no pose: sent valid or not
  const int64_t now = clock_();
  LedState state = valid                                                 ? LedState::kTracking
                   : (pose.flags & (kNotInitialised | kLocalising)) != 0 ? LedState::kInitialising
                                                                         : LedState::kLost;
  if (now < fault_until_ns_) state = LedState::kFault;
  link_.set_system_status(state == LedState::kTracking       ? mavlink::kMavStateActive
                          : state == LedState::kInitialising ? mavlink::kMavStateStandby
                                                             : mavlink::kMavStateCritical);
  led_.update(state, now);
  slam_.map_pending();  // the keyframe and the mapper's step after the pose is sent
  if (trigger) gpio_->set(board_.gpio_trigger_line, false);
  const int64_t done = clock_();
  tracker_time_.add(done - t0);
  if (done > arrival_ns + period_ns_) ++counters_.deadline_misses;
  return pose;
}

void FirmwareRuntime::on_sensor_error(const Status& error, int64_t now_ns) {
  ++counters_.sensor_errors;
  fault_until_ns_ = now_ns + 2'000'000'000;
  // A sensor that fails every read would flood the link and the operator's log: one message
  // when an outage starts, then one per interval while it lasts.
  constexpr int64_t kSensorTextIntervalNs = 5'000'000'000;
  if (sensor_text_posted_ && now_ns - sensor_text_ns_ < kSensorTextIntervalNs) {
    ++counters_.sensor_texts_withheld;
    return;
  }
  sensor_text_posted_ = true;
  sensor_text_ns_ = now_ns;
  char text[kMaxStatusTextChars + 1];
  std::snprintf(text, sizeof(text), "sensor: %s", error.message());
  post_event(mavlink::kMavSeverityError, text);
}

void FirmwareRuntime::on_sensor_recovered(int64_t outage_ns) {
  ++counters_.sensor_recoveries;
  sensor_text_posted_ = false;  // the next outage is reported at once
  char text[kMaxStatusTextChars + 1];
  std::snprintf(text, sizeof(text), "sensor: frames again after %lld ms",
                static_cast<long long>(outage_ns / 1'000'000));
  post_event(mavlink::kMavSeverityInfo, text);
}

void FirmwareRuntime::report_stores_full() {
  if (!pool_full_reported_ && slam_.tracking().keyframes().recycled() > 0) {
    pool_full_reported_ = true;
    post_event(mavlink::kMavSeverityInfo, "rgbdtam: keyframe pool full, recycling oldest");
  }
  if (!place_store_full_reported_ && slam_.places().evicted() > 0) {
    place_store_full_reported_ = true;
    char text[kMaxStatusTextChars + 1];
    std::snprintf(text, sizeof(text), "rgbdtam: place store full (%d), forgetting oldest",
                  slam_.places().capacity());
    post_event(mavlink::kMavSeverityInfo, text);
  }
}

void FirmwareRuntime::stop() {
  if (!started_) return;
  started_ = false;
  slam_.finish();
  // The loop module may have forgotten a place after the last frame's check (a slow board).
  report_stores_full();
  link_.stop();
}

}  // namespace rgbdtam

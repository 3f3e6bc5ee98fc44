#include "run_job.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <sys/stat.h>

#include <cerrno>

#include "config_files.hpp"
#include "map_files.hpp"
#include "memory_budget.hpp"
#include "rgbdtam/core/assert.hpp"
#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/fakenect_dump.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/serial_link.hpp"
#include "rgbdtam/hal/udp_link.hpp"
#include "rgbdtam/hal/usb_devices.hpp"
#include "summary_lines.hpp"

namespace rgbdtam {

Status load_board_and_params(const RunOptions& options, Board* board, Params* params) {
  if (options.board_dir == nullptr) {
    return Status::error(StatusCode::kInvalidArgument, "--board <folder> is required");
  }
  RGBDTAM_RETURN_IF_ERROR(load_board(options.board_dir, board));
  for (int i = 0; i < options.board_override_count; ++i) {
    RGBDTAM_RETURN_IF_ERROR(set_board_value(options.board_overrides[i], board));
  }
  RGBDTAM_RETURN_IF_ERROR(validate_board(*board));
  RGBDTAM_RETURN_IF_ERROR(read_params_file(board->sensor_config, params));
  for (int i = 0; i < options.param_override_count; ++i) {
    RGBDTAM_RETURN_IF_ERROR(set_param(options.param_overrides[i], "--set", params));
  }
  // As the firmware will (FirmwareRuntime::init), so that the memory budget checks the board's
  // own pool sizes.
  return apply_board_capacity(*board, params);
}

bool sensor_backend_in_build(const char* kind) {
  const size_t n = std::strlen(kind);
  for (const char* at = RGBDTAM_HAL_BACKENDS; *at != '\0';) {
    const char* end = std::strchr(at, ' ');
    if (end == nullptr) end = at + std::strlen(at);
    if (static_cast<size_t>(end - at) == n && std::strncmp(at, kind, n) == 0) return true;
    at = *end == ' ' ? end + 1 : end;
  }
  return false;
}

namespace {
// How long a device backend waits for a frame before next() reports it (a stall is longer).
constexpr int kFrameTimeoutMs = 1000;

Status open_replay(const Board& board, const Params& params, BoardSensor* sensor) {
  RGBDTAM_RETURN_IF_ERROR(sensor->replay.open(board.sensor_device, sensor_image_size(params),
                                              params.sensor.max_rgb_depth_dt_ns,
                                              params.sensor.depth_time_offset_ns));
  sensor->replay_sensor.open(&sensor->replay);
  sensor->live = &sensor->replay_sensor;
  return Status::ok();
}

Status open_v4l2(const Board& board, const Params& params, BoardSensor* sensor, V4l2Io* v4l2_io) {
  // sensor.device = <depth node>,<colour node>, or usb: found by sensor.usb_id
  char depth[kTextBytes] = "";
  const char* colour = "";
  UsbId usb;
  if (std::strcmp(board.sensor_device, "usb") == 0 && parse_usb_id(board.sensor_usb_id, &usb)) {
    sensor->v4l2.locate_by_usb(usb, board.sysfs_root, board.devfs_root);
  } else {
    const char* comma = std::strchr(board.sensor_device, ',');
    if (comma == nullptr) {
      return Status::error(
          StatusCode::kInvalidArgument,
          "board '%s': sensor.device for v4l2 is '<depth node>,<colour node>' or usb", board.name);
    }
    std::snprintf(depth, sizeof(depth), "%.*s", static_cast<int>(comma - board.sensor_device),
                  board.sensor_device);
    colour = comma + 1;
  }
  sensor->v4l2.use_camera_clock(board.sensor_clock_hz);
  RGBDTAM_RETURN_IF_ERROR(sensor->v4l2.open(
      v4l2_io != nullptr ? v4l2_io : &sensor->v4l2_io, depth, colour, sensor_image_size(params),
      params.sensor.max_rgb_depth_dt_ns, kFrameTimeoutMs,
      std::strcmp(board.sensor_colour, "mjpeg") == 0 ? V4l2Colour::kMjpeg : V4l2Colour::kYuyv));
  sensor->live = &sensor->v4l2;
  return Status::ok();
}

#if RGBDTAM_WITH_FREENECT
Status open_freenect(const Board& board, BoardSensor* sensor) {
  const FreenectDepth mode = std::strcmp(board.sensor_depth, "raw") == 0
                                 ? FreenectDepth::kRaw
                                 : FreenectDepth::kRegistered;
  // The latest of each stream pair up, whatever their stamps' distance (it is kept: the depth is
  // tracked from its own instant).
  RGBDTAM_RETURN_IF_ERROR(sensor->freenect.open(kFreenectUsbDriver, std::atoi(board.sensor_device),
                                                mode, UINT32_MAX / 2));
  sensor->live = &sensor->freenect;
  return Status::ok();
}
#endif

#if RGBDTAM_WITH_FAKENECT
Status open_fakenect(const Board& board, BoardSensor* sensor) {
  // fakenect finds its dump through the environment, plays raw disparity only, plays it once
  // per process, and exits the process on a file it cannot read: checked here first.
  const Status dump = check_fakenect_dump(board.sensor_device);
  if (!dump.is_ok()) {
    return Status::error(dump.code(), "board '%s': sensor.device: %s", board.name, dump.message());
  }
  setenv("FAKENECT_PATH", board.sensor_device, 1);
  RGBDTAM_RETURN_IF_ERROR(
      sensor->freenect.open(kFakenectDriver, 0, FreenectDepth::kRaw, UINT32_MAX / 2));
  sensor->live = &sensor->freenect;
  return Status::ok();
}
#endif

#if RGBDTAM_WITH_OPENNI2
Status open_openni2(const Board& board, const Params& params, BoardSensor* sensor) {
  RGBDTAM_RETURN_IF_ERROR(sensor->openni2.open(board.sensor_device, params.camera.width_px,
                                               params.camera.height_px,
                                               static_cast<int>(std::lround(board.sensor_fps)),
                                               params.sensor.max_rgb_depth_dt_ns, kFrameTimeoutMs));
  sensor->live = &sensor->openni2;
  return Status::ok();
}
#endif

// The board's backend, by its kind (validate_board has checked that the board names one); a
// kind this build lacks is an error naming the build's.
Status open_backend(const Board& board, const Params& params, BoardSensor* sensor,
                    V4l2Io* v4l2_io) {
  const SensorKindName* kind = find_sensor_kind(board.sensor_kind);
  RGBDTAM_ASSERT(kind != nullptr, "validate_board accepts only the kinds of kSensorKinds");
  switch (kind->kind) {
    case SensorKind::kReplay:
      return open_replay(board, params, sensor);
    case SensorKind::kV4l2:
      return open_v4l2(board, params, sensor, v4l2_io);
#if RGBDTAM_WITH_FREENECT
    case SensorKind::kFreenect:
      return open_freenect(board, sensor);
#endif
#if RGBDTAM_WITH_FAKENECT
    case SensorKind::kFakenect:
      return open_fakenect(board, sensor);
#endif
#if RGBDTAM_WITH_OPENNI2
    case SensorKind::kOpenni2:
      return open_openni2(board, params, sensor);
#endif
    default:
      break;
  }
  return missing_backend_error(board);
}
}  // namespace

Status missing_backend_error(const Board& board) {
  return Status::error(StatusCode::kInvalidArgument,
                       "board '%s': this build has no '%s' sensor backend (it has: %s)", board.name,
                       board.sensor_kind, RGBDTAM_HAL_BACKENDS);
}

Status open_board_sensor(const Board& board, const Params& params, BoardSensor* sensor,
                         V4l2Io* v4l2_io) {
  RecoveryConfig recovery;
  if (board.sensor_usb_id[0] != '\0' && parse_usb_id(board.sensor_usb_id, &recovery.usb)) {
    char what[kTextBytes + 32];
    std::snprintf(what, sizeof(what), "board '%s': sensor", board.name);
    RGBDTAM_RETURN_IF_ERROR(require_usb_device(board.sysfs_root, recovery.usb, what));
    recovery.reset_usb = true;
  }
  RGBDTAM_RETURN_IF_ERROR(open_backend(board, params, sensor, v4l2_io));
  if (board.sensor_registration_thread) {
    if (!params.depth_camera.register_to_colour) {
      return Status::error(StatusCode::kInvalidArgument,
                           "board '%s': sensor.registration_thread needs depth_camera.register = "
                           "true in its sensor.config (%s)",
                           board.name, board.sensor_config);
    }
    sensor->registering.init(sensor->live, params);
    sensor->live = &sensor->registering;
  }
  recovery.stall_ns = board.sensor_stall_ms * 1'000'000LL;
  recovery.reopen_budget_ns = board.sensor_reopen_budget_ms * 1'000'000LL;
  recovery.error_interval_ns = static_cast<int64_t>(1e9 / board.sensor_fps);
  recovery.sysfs_root = board.sysfs_root;
  recovery.devfs_root = board.devfs_root;
  sensor->recovery.init(sensor->live, recovery, monotonic_ns, sleep_until_ns);
  sensor->live = &sensor->recovery;
  return Status::ok();
}

RunJob::~RunJob() { finish(); }

Status RunJob::init(const RunOptions& options) {
  options_ = options;
  RGBDTAM_RETURN_IF_ERROR(load_board_and_params(options, &board_, &params_));
  Status vocabulary_error;
  const bool loop = load_vocabulary(params_, &vocabulary_, &vocabulary_error);
  RGBDTAM_RETURN_IF_ERROR(vocabulary_error);
  const size_t sensor_bytes =
      board_.sensor_registration_thread ? RegisteringSensor::bytes_needed(params_) : 0;
  RGBDTAM_RETURN_IF_ERROR(check_memory_budget(
      FirmwareRuntime::system_params(params_, board_), loop ? vocabulary_.words() : 0, sensor_bytes,
      0, 0, memory_budget(board_.memory_budget_mb), &memory_needed_bytes_));
  RGBDTAM_RETURN_IF_ERROR(open_board_sensor(board_, params_, &sensor_, options.v4l2_io));
  if (options.replay_every_frame) {
    sensor_.replay_sensor.hold_every_frame();
    sensor_.registering.hold_every_frame();
  }
  if (std::strcmp(board_.link_kind, "udp") == 0) {
    char ip[64];
    uint16_t port = 0;
    (void)split_endpoint(board_.link_udp_remote, ip, sizeof(ip), &port);  // validated
    auto udp = std::make_unique<UdpLink>();
    RGBDTAM_RETURN_IF_ERROR(udp->open(ip, port, 0));
    link_ = std::move(udp);
  } else {
    auto serial = std::make_unique<SerialLink>();
    RGBDTAM_RETURN_IF_ERROR(
        serial->open(board_.link_serial_device, static_cast<uint32_t>(board_.link_baud)));
    link_ = std::move(serial);
  }
  if (std::strcmp(board_.gpio_chip, "fake") == 0) {
    gpio_ = std::make_unique<FakeGpio>();
  } else if (board_.gpio_chip[0] != '\0') {
    auto chip = std::make_unique<LibgpiodOutputs>();
    const int lines[] = {board_.gpio_led_line, board_.gpio_trigger_line};
    RGBDTAM_RETURN_IF_ERROR(chip->open(board_.gpio_chip, lines, 2));
    gpio_ = std::move(chip);
  }
  runtime_ = std::make_unique<FirmwareRuntime>();
  RGBDTAM_RETURN_IF_ERROR(runtime_->init(params_, board_, link_.get(), gpio_.get(), monotonic_ns,
                                         loop ? &vocabulary_ : nullptr));
  return open_map_file(loop);
}

// The board's map: loaded when it exists; in slam mode a missing one is made at the end.
Status RunJob::open_map_file(bool loop) {
  if (board_.map_file[0] == '\0') return Status::ok();
  if (!loop) {
    return Status::error(StatusCode::kInvalidArgument,
                         "map.file %s needs loop closure (loop.enabled and a loop.vocabulary)",
                         board_.map_file);
  }
  struct stat st;
  if (::stat(board_.map_file, &st) != 0 && errno == ENOENT) {
    if (params_.map_mode == MapMode::kLocalise) {
      return Status::error(StatusCode::kNotFound,
                           "map.mode = localise needs a saved map: map.file %s does not exist",
                           board_.map_file);
    }
  } else {
    RGBDTAM_RETURN_IF_ERROR(load_map_file(board_.map_file, params_, runtime_.get(), &loaded_map_));
  }
  if (params_.map_mode != MapMode::kSlam) return Status::ok();
  RGBDTAM_RETURN_IF_ERROR(check_can_create(board_.map_file));  // saved at the end
  if (board_.map_save_period_s == 0) return Status::ok();
  RGBDTAM_RETURN_IF_ERROR(checkpoint_file_.init(board_.map_file));
  checkpoint_.init(int64_t{board_.map_save_period_s} * 1'000'000'000,
                   runtime_->slam().map_meta(map_written_by(options_.written_by)),
                   &checkpoint_file_, monotonic_ns, unix_time_ns);
  return runtime_->set_map_checkpoint(&checkpoint_);
}

Status RunJob::start() {
  RGBDTAM_RETURN_IF_ERROR(runtime_->start());
  started_ = true;
  RGBDTAM_RETURN_IF_ERROR(sensor_.live->start(board_.sensor));
  started_ns_ = last_progress_ns_ = monotonic_ns();
  return Status::ok();
}

bool RunJob::step() {
  if (stop_requested_.load() ||
      (options_.max_frames > 0 &&
       runtime_->counters().frames >= static_cast<uint32_t>(options_.max_frames))) {
    return false;
  }
  SensorFrame frame;
  Status warning;
  const Status s = sensor_.live->next(&frame, &warning);
  if (s.code() == StatusCode::kEndOfStream) return false;
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam run: %s\n", s.message());
    runtime_->on_sensor_error(s, monotonic_ns());
    return true;
  }
  if (!warning.is_ok() && options_.progress) {
    std::fprintf(stderr, "rgbdtam run: %s\n", warning.message());
  }
  const RecoveryCounters& recovery = sensor_.recovery.counters();
  if (recovery.recoveries != recoveries_reported_) {
    recoveries_reported_ = recovery.recoveries;
    runtime_->on_sensor_recovered(recovery.last_recovery_ns);
  }
  (void)runtime_->on_frame(frame, sensor_.live->arrival_ns());
  const int64_t now = monotonic_ns();
  if (options_.progress && now - last_progress_ns_ >= 1'000'000'000) {
    last_progress_ns_ = now;
    const FirmwareCounters& c = runtime_->counters();
    std::fprintf(stderr,
                 "\r%u frames, %u tracked, %u lost, %u deadline misses, %u dropped, tracker "
                 "%.1f ms median",
                 c.frames, c.tracked, c.lost, c.deadline_misses, sensor_.live->dropped(),
                 runtime_->tracker_time().percentile_ms(0.5));
  }
  return true;
}

void RunJob::finish() {
  // After a failed init nothing ran, and the map file (maybe the one that failed to load)
  // stays as it is.
  if (finished_ || !started_) return;
  finished_ = true;
  wall_ns_ = monotonic_ns() - started_ns_;
  sensor_.live->stop();
  runtime_->stop();
  if (board_.map_file[0] != '\0' && params_.map_mode == MapMode::kSlam) {
    map_saved_ = save_map_file(board_.map_file, runtime_->slam(), options_.written_by);
  }
  if (options_.progress) std::fprintf(stderr, "\n");
}

namespace {
const char* autopilot_name(uint8_t autopilot) {
  switch (autopilot) {
    case 3:
      return "ArduPilot";
    case 12:
      return "PX4";
    case 8:
      return "not an autopilot";
    default:
      return "other";
  }
}

void print_peer(const PeerState& p) {
  if (!p.heard) {
    std::printf("autopilot: none heard (%llu frames received)\n",
                static_cast<unsigned long long>(p.frames));
    return;
  }
  std::printf(
      "autopilot: system %u component %u, MAV_AUTOPILOT %u (%s), MAV_TYPE %u; %u "
      "heartbeats, silent %u times%s\n",
      p.system_id, p.component_id, p.autopilot, autopilot_name(p.autopilot), p.type, p.heartbeats,
      p.silences, p.silent ? " (silent at the end)" : "");
  std::printf(
      "timesync: %u of its requests answered; %u answers to ours used, %u too slow to use (%u "
      "clock jumps)",
      p.timesync_answered, p.timesync_replies, p.timesync_delayed, p.clock_jumps);
  if (p.clock_known) {
    std::printf(", its clock %+.3f ms from our time_usec, best round trip %.3f ms",
                static_cast<double>(p.clock_offset_ns) * 1e-6,
                static_cast<double>(p.best_round_trip_ns) * 1e-6);
  }
  std::printf("\n");
}
void print_attitude(const FirmwareRuntime& runtime, const PoseLinkCounters& lc) {
  const AttitudeAidCounters& a = runtime.attitude().counters();
  const TrackingCounters& t = runtime.slam().tracking().counters();
  std::printf(
      "attitude: %llu from the autopilot (%llu handed to the tracker, %llu before TIMESYNC, "
      "%llu dropped at its full queue), %u kept, %u refused; "
      "frame %s (%u levellings, reset_counter moved %u times); rotation prior on %u frames: "
      "%u stood, %u refused by the image",
      static_cast<unsigned long long>(lc.attitudes + lc.attitudes_unsynced + lc.attitudes_dropped),
      static_cast<unsigned long long>(lc.attitudes),
      static_cast<unsigned long long>(lc.attitudes_unsynced),
      static_cast<unsigned long long>(lc.attitudes_dropped), a.samples, a.refused,
      runtime.attitude().levelled() ? "levelled by gravity" : "the body at the first frame",
      a.levellings, lc.frame_changes, a.priors, t.prior_used, t.prior_rejected);
  if (lc.held_unsynced > 0 || lc.origins_sent > 0) {
    std::printf("; %llu held for TIMESYNC; origin sent %llu times",
                static_cast<unsigned long long>(lc.held_unsynced),
                static_cast<unsigned long long>(lc.origins_sent));
  }
  std::printf("\n");
}
}  // namespace

namespace {
void print_v4l2_summary(const V4l2Source& v4l2) {
  const V4l2Nodes& n = v4l2.nodes();
  const V4l2Counters& c = v4l2.counters();
  std::printf("v4l2: depth %s, colour %s", n.depth, n.colour);
  if (v4l2.reads_metadata()) {
    std::printf(
        " (metadata %s %s: %u pairs on the camera's clock, %u frames without metadata, "
        "%u metadata buffers flagged as errors, %u frames lost before the driver)",
        n.depth_metadata, n.colour_metadata, c.camera_stamped, c.metadata_missing,
        c.metadata_errors, c.lost_before_driver);
  } else if (n.depth_metadata[0] != '\0' || n.colour_metadata[0] != '\0') {
    std::printf(" (their metadata nodes, not read without sensor.clock_hz: %s %s)",
                n.depth_metadata, n.colour_metadata);
  }
  std::printf(
      "; depth minus colour stamp %+.1f ms mean (%+.1f to %+.1f) over %u pairs, %u unpaired, %u "
      "requeues refused, %u error buffers\n",
      c.mean_pair_offset_ns() * 1e-6, c.pair_offset_min_ns * 1e-6, c.pair_offset_max_ns * 1e-6,
      c.delivered, c.unpaired, c.requeue_failures, c.error_buffers);
}
}  // namespace

void RunJob::print_summary() const {
  const FirmwareCounters& c = runtime_->counters();
  const double seconds = wall_ns_ * 1e-9;
  std::printf("board: %s (%s); sensor %s at %.0f Hz, link %s %s\n", board_.name, board_.description,
              board_.sensor_kind, board_.sensor_fps, board_.link_kind,
              std::strcmp(board_.link_kind, "udp") == 0 ? board_.link_udp_remote
                                                        : board_.link_serial_device);
  char withheld[96] = "";
  if (c.sensor_texts_withheld > 0) {
    std::snprintf(withheld, sizeof(withheld), " (%u not posted: the outage was reported lately)",
                  c.sensor_texts_withheld);
  }
  std::printf(
      "frames: %u in %.1f s (%.1f Hz); tracked %u, lost %u; sensor errors %u%s, dropped (newest "
      "kept) %u\n",
      c.frames, seconds, seconds > 0 ? c.frames / seconds : 0.0, c.tracked, c.lost, c.sensor_errors,
      withheld, sensor_.live->dropped());
  warn_about_depth(runtime_->slam().tracking(), "rgbdtam run");
  if (std::strcmp(board_.sensor_kind, "v4l2") == 0) print_v4l2_summary(sensor_.v4l2);
  const RecoveryCounters& r = sensor_.recovery.counters();
  std::printf(
      "sensor recovery: %u stalls, %u USB resets (%u failed), %u reopens (%u failed), %u "
      "recovered, longest outage %.0f ms\n",
      r.stalls, r.usb_resets, r.usb_reset_failures, r.reopens, r.reopen_failures, r.recoveries,
      r.max_recovery_ns * 1e-6);
  std::printf("memory: %.0f MB allocated at init for the SLAM system (budget: %s)\n",
              static_cast<double>(memory_needed_bytes_) / (1 << 20),
              memory_budget(board_.memory_budget_mb).from);
  std::printf("cadence: %u deadline misses (deadline %.1f ms after arrival)\n", c.deadline_misses,
              1e3 / board_.sensor_fps);
  print_task_times();
  print_loop_summary(runtime_->slam());
  if (board_.map_file[0] != '\0') print_map_file_summary();
  print_link_summary();
  std::printf("gpio: status LED %u transitions\n", runtime_->led().transitions());
}

void RunJob::print_task_times() const {
  char spread[96];
  std::printf("tracker task ms: %s\n",
              runtime_->tracker_time().describe(2, spread, sizeof(spread)));
  const LatencyStats& latency = runtime_->link().arrival_to_odometry();
  std::printf("latency, frame arrival to ODOMETRY sent, ms: %s over %lld\n",
              latency.describe(2, spread, sizeof(spread)), static_cast<long long>(latency.count()));
  const MappingModule& m = runtime_->slam().mapper();
  const TrackingCounters& tracking = runtime_->slam().tracking().counters();
  std::printf(
      "mapper task ms/keyframe: %s over %u keyframes; %u frames skipped to catch up, %u frames "
      "(%u keyframes) dropped at its full queue\n",
      m.time_per_keyframe().describe(1, spread, sizeof(spread)), m.counters().keyframes_mapped,
      m.counters().frames_skipped_late, tracking.mapper_dropped_frames,
      tracking.mapper_dropped_keyframes);
  const LatencyStats& builds = runtime_->slam().keyframe_building().time_per_keyframe();
  std::printf(
      "keyframe builder ms/keyframe: %s over %lld; %u frames tracked against the last keyframe "
      "while the next was built, %u built stale\n",
      builds.describe(1, spread, sizeof(spread)), static_cast<long long>(builds.count()),
      tracking.frames_awaiting_keyframe, tracking.keyframes_stale);
}

Status RunJob::final_map_save() const {
  if (map_saved_.is_ok()) return map_saved_;
  const char* kept = checkpoint_.saves() > 0  ? "the last save made while running"
                     : loaded_map_.places > 0 ? "the map loaded at start"
                                              : "nothing from this run";
  return Status::error(map_saved_.code(), "map.file %s was not saved at the end (%s): it holds %s",
                       board_.map_file, map_saved_.message(), kept);
}

void RunJob::print_map_file_summary() const {
  const bool localise = params_.map_mode == MapMode::kLocalise;
  const bool failed = checkpoint_.failures() > 0;
  std::printf("map file: %s: %u places loaded%s; %s; %u saves while running, %u failed%s%s\n",
              board_.map_file, loaded_map_.places, localise ? " (localise: never written)" : "",
              localise             ? "left as it was"
              : map_saved_.is_ok() ? "saved at the end"
                                   : map_saved_.message(),
              checkpoint_.saves(), checkpoint_.failures(), failed ? ", the last: " : "",
              failed ? checkpoint_.last_failure().message() : "");
}

void RunJob::print_link_summary() const {
  using ull = unsigned long long;
  const LinkTask& l = runtime_->link();
  const PoseLinkCounters& lc = l.counters();
  const LinkCounters& tc = link_->counters();
  char spread[96];
  std::printf("link task ms/message: %s\n",
              l.time_per_message().describe(3, spread, sizeof(spread)));
  std::printf(
      "link: ODOMETRY %llu sent, %llu rate-limited, %llu refused; OBSTACLE_DISTANCE %llu "
      "sent, %llu rate-limited, %llu refused; HEARTBEAT %llu, STATUSTEXT %llu; queue drops %llu; "
      "transport tx %llu frames %llu bytes, drops %llu, errors %llu\n",
      ull{lc.odometry_sent}, ull{lc.odometry_rate_limited}, ull{lc.odometry_refused},
      ull{lc.obstacles_sent}, ull{lc.obstacles_rate_limited}, ull{lc.obstacles_refused},
      ull{lc.heartbeats_sent}, ull{lc.status_texts_sent}, ull{l.queue_drops()}, ull{tc.tx_frames},
      ull{tc.tx_bytes}, ull{tc.drops}, ull{tc.errors});
  if (tc.errors > 0) {
    // "Sent" above is what the link was given; say what the transport did not deliver, and why.
    std::printf("link errors: %llu failed calls, %llu queued bytes lost; last: %s\n",
                ull{tc.errors}, ull{tc.lost_bytes}, std::strerror(tc.last_error));
  }
  print_peer(l.peer());
  print_attitude(*runtime_, lc);
}

}  // namespace rgbdtam

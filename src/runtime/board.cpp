#include "rgbdtam/runtime/board.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace rgbdtam {
namespace {

#define RGBDTAM_FIELD(expr) [](void* b) -> void* { return &static_cast<Board*>(b)->expr; }
#define RGBDTAM_TEXT(key, doc, expr, required) \
  { key, ValueType::kText, 0, 0, "", doc, RGBDTAM_FIELD(expr), required }

const KeySpec kBoardSpecs[] = {
    RGBDTAM_TEXT("board.name", "the board's name", name, true),
    RGBDTAM_TEXT("board.description", "what it is", description, false),
    RGBDTAM_TEXT("build.cpu", "-mcpu of its build, e.g. cortex-a72 (host: empty)", cpu, false),
    RGBDTAM_TEXT("build.preset", "the CMake preset that builds for it", preset, true),
    {"board.cpu_count", ValueType::kInt, 1, 256, "", "CPU cores thread placement may name",
     RGBDTAM_FIELD(cpu_count), true},
    RGBDTAM_TEXT("sensor.kind", "the sensor backend (docs/sensors.md)", sensor_kind, true),
    RGBDTAM_TEXT(
        "sensor.device",
        "replay: TUM folder; fakenect: libfreenect dump folder; v4l2: '<depth node>,<colour "
        "node>' or usb (found by sensor.usb_id); else device path or URI",
        sensor_device, true),
    RGBDTAM_TEXT("sensor.config", "camera and tracking params file", sensor_config, true),
    RGBDTAM_TEXT("sensor.colour", "v4l2: the colour node's format, yuyv or mjpeg", sensor_colour,
                 false),
    RGBDTAM_TEXT("sensor.depth", "freenect: registered (mm, device calibration) or raw",
                 sensor_depth, false),
    RGBDTAM_TEXT("sensor.usb_id", "vendor:product (hex) that must be attached, e.g. 045e:02ae",
                 sensor_usb_id, false),
    RGBDTAM_TEXT("map.file",
                 "saved map: loaded at start when it exists, saved at the end (map.mode slam)",
                 map_file, false),
    {"map.save_period_s", ValueType::kInt, 0, 86400, "s",
     "map.file is also saved this often while running, by the loop thread (0: only at the end)",
     RGBDTAM_FIELD(map_save_period_s), false},
    RGBDTAM_TEXT("board.sysfs_root", "where sysfs is mounted (/sys)", sysfs_root, false),
    RGBDTAM_TEXT("board.devfs_root", "where /dev is (usbfs nodes for a USB reset)", devfs_root,
                 false),
    {"sensor.fps", ValueType::kReal, 1, 120, "Hz", "frame rate: the tracking cadence",
     RGBDTAM_FIELD(sensor_fps), false},
    {"sensor.clock_hz", ValueType::kReal, 0, 1e9, "Hz",
     "v4l2: the camera clock's rate in its UVC metadata (D4xx: 1000000); frames are stamped and "
     "paired on it (0: by arrival)",
     RGBDTAM_FIELD(sensor_clock_hz), false},
    {"sensor.registration_thread", ValueType::kBool, 0, 1, "",
     "depth registered to colour (depth_camera.register) on the sensor's own thread, beside "
     "tracking, instead of on the tracker's",
     RGBDTAM_FIELD(sensor_registration_thread), false},
    {"sensor.stall_ms", ValueType::kInt, 100, 60000, "ms",
     "no frame for this long: USB reset (with sensor.usb_id) and reopen",
     RGBDTAM_FIELD(sensor_stall_ms), false},
    {"sensor.reopen_budget_ms", ValueType::kInt, 0, 60000, "ms",
     "reopen attempts after a stall, within this time", RGBDTAM_FIELD(sensor_reopen_budget_ms),
     false},
    {"memory.budget_mb", ValueType::kInt, 0, 1 << 20, "MB",
     "what init may allocate (0: half of the machine's memory)", RGBDTAM_FIELD(memory_budget_mb),
     false},
    RGBDTAM_TEXT("link.kind", "udp or serial", link_kind, true),
    RGBDTAM_TEXT("link.udp_remote", "udp: controller endpoint ip:port", link_udp_remote, false),
    RGBDTAM_TEXT("link.serial_device", "serial: the port, e.g. /dev/ttyAMA0", link_serial_device,
                 false),
    {"link.baud", ValueType::kInt, 9600, 3000000, "baud", "serial: line rate",
     RGBDTAM_FIELD(link_baud), false},
    {"link.system_id", ValueType::kInt, 1, 255, "", "MAVLink system id",
     RGBDTAM_FIELD(link_system_id), false},
    {"link.component_id", ValueType::kInt, 1, 255, "", "MAVLink component id",
     RGBDTAM_FIELD(link_component_id), false},
    {"link.T_b_c", ValueType::kCustom, 0, 0, "",
     "body from camera: qw qx qy qz (unit) tx ty tz (m, each within 10)", RGBDTAM_FIELD(T_b_c),
     false, parse_pose_value, print_pose_value},
    {"obstacle.rate_hz", ValueType::kReal, 0, 30, "Hz",
     "OBSTACLE_DISTANCE from the depth image this often (0: never)",
     RGBDTAM_FIELD(obstacle_rate_hz), false},
    {"obstacle.lowest_m", ValueType::kReal, -10, 10, "m",
     "obstacles: lowest point above the body (link.T_b_c), up positive",
     RGBDTAM_FIELD(obstacle_lowest_m), false},
    {"obstacle.highest_m", ValueType::kReal, -10, 10, "m",
     "obstacles: highest point above the body", RGBDTAM_FIELD(obstacle_highest_m), false},
    {"obstacle.fov_deg", ValueType::kReal, 0, 180, "deg",
     "span of the 72 sectors, centred on the camera's bearing (0: its horizontal field of view)",
     RGBDTAM_FIELD(obstacle_fov_deg), false},
    {"autopilot.attitude", ValueType::kBool, 0, 1, "",
     "use the autopilot's ATTITUDE(_QUATERNION): level ODOMETRY's frame, prior for turns",
     RGBDTAM_FIELD(autopilot_attitude), false},
    {"autopilot.attitude_sigma", ValueType::kDegreesAsRadians, 0.01, 10, "deg",
     "the autopilot's attitude noise over one frame (the prior's gate is 3 of these)",
     RGBDTAM_FIELD(autopilot_attitude_sigma_rad), false},
    {"link.time_in_autopilot_clock", ValueType::kBool, 0, 1, "",
     "time_usec in the autopilot's clock by TIMESYNC (held back until it answers)",
     RGBDTAM_FIELD(link_time_in_autopilot_clock), false},
    {"origin.latitude_deg", ValueType::kReal, -90, 90, "deg",
     "geographic origin sent as SET_GPS_GLOBAL_ORIGIN when the autopilot is heard (WGS84)",
     RGBDTAM_FIELD(origin_latitude_deg), false},
    {"origin.longitude_deg", ValueType::kReal, -180, 180, "deg", "its longitude (WGS84)",
     RGBDTAM_FIELD(origin_longitude_deg), false},
    {"origin.altitude_m", ValueType::kReal, -1000, 10000, "m",
     "its altitude above mean sea level (with the latitude; 0 when not set)",
     RGBDTAM_FIELD(origin_altitude_m), false},
    RGBDTAM_TEXT("gpio.chip", "GPIO chip device (empty: no GPIO)", gpio_chip, false),
    {"gpio.led_line", ValueType::kInt, -1, 1023, "", "status LED line (-1: none)",
     RGBDTAM_FIELD(gpio_led_line), false},
    {"gpio.trigger_line", ValueType::kInt, -1, 1023, "", "frame trigger line (-1: none)",
     RGBDTAM_FIELD(gpio_trigger_line), false},
    {"threads.tracker_cpu", ValueType::kInt, -1, 255, "", "tracker CPU (-1: any)",
     RGBDTAM_FIELD(tracker.cpu), false},
    {"threads.tracker_priority", ValueType::kInt, 0, 99, "", "tracker SCHED_FIFO (0: normal)",
     RGBDTAM_FIELD(tracker.priority), false},
    {"threads.builder_cpu", ValueType::kInt, -1, 255, "", "keyframe builder CPU (-1: any)",
     RGBDTAM_FIELD(builder.cpu), false},
    {"threads.builder_priority", ValueType::kInt, 0, 99, "",
     "keyframe builder SCHED_FIFO (0: normal)", RGBDTAM_FIELD(builder.priority), false},
    {"threads.mapper_cpu", ValueType::kInt, -1, 255, "", "mapper CPU (-1: any)",
     RGBDTAM_FIELD(mapper.cpu), false},
    {"threads.mapper_priority", ValueType::kInt, 0, 99, "", "mapper SCHED_FIFO (0: normal)",
     RGBDTAM_FIELD(mapper.priority), false},
    {"threads.loop_cpu", ValueType::kInt, -1, 255, "", "loop-closure CPU (-1: any)",
     RGBDTAM_FIELD(loop.cpu), false},
    {"threads.loop_priority", ValueType::kInt, 0, 99, "", "loop-closure SCHED_FIFO (0: normal)",
     RGBDTAM_FIELD(loop.priority), false},
    {"threads.link_cpu", ValueType::kInt, -1, 255, "", "link CPU (-1: any)",
     RGBDTAM_FIELD(link.cpu), false},
    {"threads.link_priority", ValueType::kInt, 0, 99, "", "link SCHED_FIFO (0: normal)",
     RGBDTAM_FIELD(link.priority), false},
    {"threads.sensor_cpu", ValueType::kInt, -1, 255, "", "sensor driver CPU (-1: any)",
     RGBDTAM_FIELD(sensor.cpu), false},
    {"threads.sensor_priority", ValueType::kInt, 0, 99, "", "sensor driver SCHED_FIFO (0: normal)",
     RGBDTAM_FIELD(sensor.priority), false},
    {"capacity.keyframe_pool", ValueType::kInt, 0, 4096, "", "override map.keyframe_pool (0: keep)",
     RGBDTAM_FIELD(keyframe_pool), false},
    {"capacity.map_queue_frames", ValueType::kInt, 0, 64, "", "override map.queue_frames (0: keep)",
     RGBDTAM_FIELD(map_queue_frames), false},
    {"capacity.map_seeds", ValueType::kInt, 0, 100000, "", "override map.seeds (0: keep)",
     RGBDTAM_FIELD(map_seeds), false},
    {"capacity.loop_places", ValueType::kInt, 0, 100000, "", "override loop.places (0: keep)",
     RGBDTAM_FIELD(loop_places), false},
    {"capacity.finest_tracked_level", ValueType::kInt, 0, 1, "",
     "1: iterate down to 320x240 only (the small-board profile; 0: full resolution)",
     RGBDTAM_FIELD(finest_tracked_level), false},
    {"capacity.photometric_points", ValueType::kInt, 0, 1000000, "",
     "override tracker.photometric_points (0: keep)", RGBDTAM_FIELD(photometric_points), false},
    {"capacity.local_window", ValueType::kBool, 0, 1, "",
     "false: loop.window off (for a tracker's core with no room to track on the map it refines)",
     RGBDTAM_FIELD(local_window), false},
};
#undef RGBDTAM_TEXT
#undef RGBDTAM_FIELD

constexpr KeyTable kBoardTable{kBoardSpecs, sizeof(kBoardSpecs) / sizeof(kBoardSpecs[0])};

bool one_of(const char* value, const char* const* options, int n) {
  for (int i = 0; i < n; ++i)
    if (std::strcmp(value, options[i]) == 0) return true;
  return false;
}

// Prefixes a relative path with dir (in place); false when the result does not fit.
bool resolve(char* path, const char* dir) {
  if (path[0] == '\0' || path[0] == '/' || std::strchr(path, ':') != nullptr) return true;
  char joined[kTextBytes];
  const int n = std::snprintf(joined, sizeof(joined), "%s/%s", dir, path);
  if (n < 0 || n >= kTextBytes) return false;
  std::memcpy(path, joined, static_cast<size_t>(n) + 1);
  return true;
}

// replay and fakenect read a folder, written relative to the board folder.
bool sensor_device_is_a_folder(const Board& b) {
  const SensorKindName* kind = find_sensor_kind(b.sensor_kind);
  return kind != nullptr && kind->device_is_a_folder;
}
}  // namespace

const SensorKindName* find_sensor_kind(const char* name) {
  for (const SensorKindName& k : kSensorKinds) {
    if (std::strcmp(name, k.name) == 0) return &k;
  }
  return nullptr;
}

Status parse_board(const char* text, const char* source, const char* board_dir, Board* out) {
  Board b;
  RGBDTAM_RETURN_IF_ERROR(parse_key_values(text, source, kBoardTable, &b));
  if (std::snprintf(b.directory, sizeof(b.directory), "%s", board_dir) >= kTextBytes) {
    return Status::error(StatusCode::kInvalidArgument, "%s: folder path too long", source);
  }
  // A replay folder, params file or device path written relative to the board folder.
  if (!resolve(b.sensor_config, board_dir) || !resolve(b.map_file, board_dir) ||
      (sensor_device_is_a_folder(b) && !resolve(b.sensor_device, board_dir))) {
    return Status::error(StatusCode::kInvalidArgument, "%s: a resolved path is too long", source);
  }
  *out = b;
  return Status::ok();
}

void print_board(const Board& in, char* buf, int size, KeyListing listing) {
  Board b = in;
  print_key_values(kBoardTable, &b, buf, size, listing);
}

Status set_board_value(const char* assignment, Board* out) {
  RGBDTAM_RETURN_IF_ERROR(apply_key_value(assignment, "--board-set", kBoardTable, out));
  // A path means what it means in the board file: relative to the board folder.
  const char* key = assignment;
  while (*key == ' ' || *key == '\t') ++key;
  auto is = [&](const char* name) {
    const size_t n = std::strlen(name);
    return std::strncmp(key, name, n) == 0 && (key[n] == '=' || key[n] == ' ' || key[n] == '\t');
  };
  if ((is("sensor.config") && !resolve(out->sensor_config, out->directory)) ||
      (is("map.file") && !resolve(out->map_file, out->directory)) ||
      (is("sensor.device") && sensor_device_is_a_folder(*out) &&
       !resolve(out->sensor_device, out->directory))) {
    return Status::error(StatusCode::kInvalidArgument, "--board-set %s: resolved path too long",
                         assignment);
  }
  return Status::ok();
}

bool split_endpoint(const char* endpoint, char* ip, int ip_size, uint16_t* port) {
  const char* colon = std::strrchr(endpoint, ':');
  if (colon == nullptr || colon == endpoint || colon - endpoint >= ip_size) return false;
  char* end = nullptr;
  const long p = std::strtol(colon + 1, &end, 10);
  if (end == colon + 1 || *end != '\0' || p < 1 || p > 65535) return false;
  std::memcpy(ip, endpoint, static_cast<size_t>(colon - endpoint));
  ip[colon - endpoint] = '\0';
  *port = static_cast<uint16_t>(p);
  return true;
}

Status validate_board(const Board& b) {
  static const char* const kLinks[] = {"udp", "serial"};
  if (find_sensor_kind(b.sensor_kind) == nullptr) {
    char kinds[96] = "";
    for (const SensorKindName& k : kSensorKinds) {
      std::snprintf(kinds + std::strlen(kinds), sizeof(kinds) - std::strlen(kinds), "%s%s",
                    kinds[0] != '\0' ? ", " : "", k.name);
    }
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': sensor.kind '%s' is not one of %s", b.name, b.sensor_kind,
                         kinds);
  }
  // Required keys may still be given empty (--board-set sensor.device=); the backend would
  // then report a path it made up.
  if (b.sensor_device[0] == '\0') {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': sensor.device is empty: name the %s sensor (docs/sensors.md)",
                         b.name, b.sensor_kind);
  }
  if (b.sensor_config[0] == '\0') {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': sensor.config is empty: name the camera's params file "
                         "(config/)",
                         b.name);
  }
  unsigned vendor = 0, product = 0;
  int used = 0;
  if (b.sensor_usb_id[0] != '\0' &&
      (std::sscanf(b.sensor_usb_id, "%4x:%4x%n", &vendor, &product, &used) != 2 ||
       b.sensor_usb_id[used] != '\0')) {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': sensor.usb_id '%s' is not vendor:product in hex", b.name,
                         b.sensor_usb_id);
  }
  if (std::strcmp(b.sensor_kind, "v4l2") == 0 && std::strcmp(b.sensor_device, "usb") == 0 &&
      b.sensor_usb_id[0] == '\0') {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': sensor.device = usb finds the camera's nodes by its USB id: "
                         "set sensor.usb_id (e.g. 8086:0b07 for a RealSense D435)",
                         b.name);
  }
  static const char* const kColours[] = {"yuyv", "mjpeg"};
  if (!one_of(b.sensor_colour, kColours, 2)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': sensor.colour '%s' is not yuyv or mjpeg", b.name,
                         b.sensor_colour);
  }
  static const char* const kDepthModes[] = {"registered", "raw"};
  if (!one_of(b.sensor_depth, kDepthModes, 2)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': sensor.depth '%s' is not registered or raw", b.name,
                         b.sensor_depth);
  }
  if (b.obstacle_lowest_m >= b.obstacle_highest_m) {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': obstacle.lowest_m (%.2f) must be below obstacle.highest_m "
                         "(%.2f)",
                         b.name, b.obstacle_lowest_m, b.obstacle_highest_m);
  }
  if (std::isnan(b.origin_latitude_deg) != std::isnan(b.origin_longitude_deg)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': origin.latitude_deg and origin.longitude_deg go together",
                         b.name);
  }
  if (!std::isnan(b.origin_altitude_m) && std::isnan(b.origin_latitude_deg)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': origin.altitude_m needs origin.latitude_deg and "
                         "origin.longitude_deg (an altitude alone gives the autopilot no origin)",
                         b.name);
  }
  if (!one_of(b.link_kind, kLinks, 2)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': link.kind '%s' is not udp or serial", b.name, b.link_kind);
  }
  if (std::strcmp(b.link_kind, "udp") == 0) {
    char ip[64];
    uint16_t port = 0;
    if (!split_endpoint(b.link_udp_remote, ip, sizeof(ip), &port)) {
      return Status::error(StatusCode::kInvalidArgument,
                           "board '%s': link.udp_remote '%s' is not ip:port", b.name,
                           b.link_udp_remote);
    }
  } else if (b.link_serial_device[0] == '\0') {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': link.kind serial needs link.serial_device", b.name);
  }
  const struct {
    const char* key;
    const ThreadPlacement& t;
  } threads[] = {{"threads.tracker_cpu", b.tracker}, {"threads.builder_cpu", b.builder},
                 {"threads.mapper_cpu", b.mapper},   {"threads.loop_cpu", b.loop},
                 {"threads.link_cpu", b.link},       {"threads.sensor_cpu", b.sensor}};
  for (const auto& t : threads) {
    if (t.t.cpu >= b.cpu_count) {
      return Status::error(StatusCode::kInvalidArgument,
                           "board '%s': %s is %d, but the board has %d CPUs (0-%d)", b.name, t.key,
                           t.t.cpu, b.cpu_count, b.cpu_count - 1);
    }
  }
  if (b.builder.cpu >= 0 && b.builder.cpu == b.tracker.cpu) {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': threads.builder_cpu is the tracker's CPU (%d): the keyframe "
                         "builder is there to keep its work off that core",
                         b.name, b.tracker.cpu);
  }
  if ((b.gpio_led_line >= 0 || b.gpio_trigger_line >= 0) && b.gpio_chip[0] == '\0') {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': GPIO lines are set but gpio.chip is empty", b.name);
  }
  if (b.gpio_led_line >= 0 && b.gpio_led_line == b.gpio_trigger_line) {
    return Status::error(StatusCode::kInvalidArgument,
                         "board '%s': gpio.led_line and gpio.trigger_line are both %d", b.name,
                         b.gpio_led_line);
  }
  return Status::ok();
}

Status apply_board_capacity(const Board& b, Params* p) {
  const struct {
    const char* key;
    int value;
  } overrides[] = {{"map.keyframe_pool", b.keyframe_pool},
                   {"map.queue_frames", b.map_queue_frames},
                   {"map.seeds", b.map_seeds},
                   {"loop.places", b.loop_places},
                   {"tracker.photometric_points", b.photometric_points}};
  char source[kTextBytes + 16];
  std::snprintf(source, sizeof(source), "board '%s'", b.name);
  for (const auto& o : overrides) {
    if (o.value == 0) continue;
    char assignment[64];
    std::snprintf(assignment, sizeof(assignment), "%s=%d", o.key, o.value);
    RGBDTAM_RETURN_IF_ERROR(set_param(assignment, source, p));
  }
  if (b.finest_tracked_level == 1)
    RGBDTAM_RETURN_IF_ERROR(set_param("tracker.iterations_l0=0", source, p));
  if (!b.local_window) RGBDTAM_RETURN_IF_ERROR(set_param("loop.window=false", source, p));
  return Status::ok();
}

}  // namespace rgbdtam

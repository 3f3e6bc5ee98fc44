#pragma once
// A board definition (board/<name>/board.conf): the target's CPU and build preset, sensor,
// pose link, GPIO lines, thread placement and capacity overrides, read with the same
// `key = value` schema machinery as params and validated at start-up. Boards are data: no code
// in src/ knows a board by name.

#include <cmath>

#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/core/status.hpp"
#include "rgbdtam/port/thread_placement.hpp"
#include "rgbdtam/runtime/key_value.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

// The sensor backends a board may name in sensor.kind, all of them here. A build has those
// CMakeLists.txt enables (rgbdtam_backend; `rgbdtam check` names them).
enum class SensorKind : uint8_t { kReplay, kV4l2, kFreenect, kFakenect, kOpenni2 };
struct SensorKindName {
  SensorKind kind;
  const char* name;
  bool device_is_a_folder;  // sensor.device names a folder, relative to the board folder
};
constexpr SensorKindName kSensorKinds[] = {
    {SensorKind::kReplay, "replay", true},      {SensorKind::kV4l2, "v4l2", false},
    {SensorKind::kFreenect, "freenect", false}, {SensorKind::kFakenect, "fakenect", true},
    {SensorKind::kOpenni2, "openni2", false},
};
// The kind sensor.kind names; null when it names none.
const SensorKindName* find_sensor_kind(const char* name);

struct Board {
  char name[kTextBytes] = "";
  char description[kTextBytes] = "";
  char cpu[kTextBytes] = "";     // -mcpu for its preset, e.g. cortex-a72
  char preset[kTextBytes] = "";  // the CMake preset that builds for it
  int cpu_count = 1;             // cores the thread placement may name
  int memory_budget_mb = 0;      // what init may allocate; 0: half of the machine's memory

  char sensor_kind[kTextBytes] = "";             // one of kSensorKinds
  char sensor_device[kTextBytes] = "";           // replay: a TUM folder; else a device path or URI
  char sensor_config[kTextBytes] = "";           // the camera/tracking params file (config/)
  char sensor_colour[kTextBytes] = "yuyv";       // v4l2: yuyv or mjpeg (the colour node's format)
  char sensor_depth[kTextBytes] = "registered";  // freenect: registered (mm) or raw (11-bit)
  char sensor_usb_id[kTextBytes] = "";           // vvvv:pppp that must be attached; "" = none
  char map_file[kTextBytes] = "";        // a saved map to start in and to save to; "" = none
  int map_save_period_s = 60;            // saves while running (0: only at the end)
  char sysfs_root[kTextBytes] = "/sys";  // where sysfs is mounted
  char devfs_root[kTextBytes] = "/dev";  // where devtmpfs is (usbfs nodes for a reset)
  double sensor_fps = 30.0;
  double sensor_clock_hz = 0.0;             // v4l2: the camera clock in its metadata; 0: not used
  bool sensor_registration_thread = false;  // registration on the sensor's thread (run only)
  int sensor_stall_ms = 1000;               // no frame for this long: reset and reopen the sensor
  int sensor_reopen_budget_ms = 3000;       // reopen attempts after a reset, within this time

  char link_kind[kTextBytes] = "";        // udp | serial
  char link_udp_remote[kTextBytes] = "";  // ip:port
  char link_serial_device[kTextBytes] = "";
  int link_baud = 921600;
  int link_system_id = 1;
  int link_component_id = 197;  // MAV_COMP_ID_VISUAL_INERTIAL_ODOMETRY
  SE3 T_b_c;                    // body from camera; "qw qx qy qz tx ty tz"
  // OBSTACLE_DISTANCE from the depth image (0 Hz: not sent), in link.T_b_c's body frame.
  double obstacle_rate_hz = 10.0;
  double obstacle_lowest_m = -0.5, obstacle_highest_m = 0.5;  // the height band, up positive
  double obstacle_fov_deg = 0.0;                              // 0: the camera's
  // The autopilot's attitude (ATTITUDE_QUATERNION or ATTITUDE): gravity levels ODOMETRY's
  // frame, and the turn between frames is the tracker's first guess, checked by the image.
  bool autopilot_attitude = true;
  double autopilot_attitude_sigma_rad = 0.5 * M_PI / 180.0;  // its noise over one frame
  bool link_time_in_autopilot_clock = false;  // time_usec in the autopilot's clock (TIMESYNC)
  // A fixed geographic origin sent as SET_GPS_GLOBAL_ORIGIN (NaN: none).
  double origin_latitude_deg = NAN, origin_longitude_deg = NAN, origin_altitude_m = NAN;

  char gpio_chip[kTextBytes] = "";  // empty: no GPIO
  int gpio_led_line = -1;           // status LED, -1 = none
  int gpio_trigger_line = -1;       // frame trigger output to the sensor, -1 = none

  ThreadPlacement tracker, builder, mapper, loop, link, sensor;

  // Capacity overrides on the params (0 = keep the params file's value).
  int keyframe_pool = 0;
  int map_queue_frames = 0;
  int map_seeds = 0;
  int loop_places = 0;
  // The small-board profile: tracking iterates down to 320x240 only (the 640x480 level is
  // evaluated once, for the health checks and the pose's information), with fewer points.
  int finest_tracked_level = 0;
  int photometric_points = 0;
  // false: the local window stays off (loop.window), for a tracker's core with no room to track
  // on the map it refines (board/raspberry-pi-4/board.conf says why).
  bool local_window = true;

  char directory[kTextBytes] = "";  // the board folder; relative paths in the file start here
};

// Parses a board file's text (source names it in errors) and resolves its relative paths
// against board_dir (the folder the file is in).
Status parse_board(const char* text, const char* source, const char* board_dir, Board* out);
// One `key=value` override, e.g. from the command line; a relative path is relative to the
// board folder, as in the board file.
Status set_board_value(const char* assignment, Board* out);
// Every board key with the board's value, unit and meaning (as print_params does for params).
void print_board(const Board& b, char* buf, int size, KeyListing listing = KeyListing::kFile);
// Consistency checks beyond each key's own range (names the board and the key).
Status validate_board(const Board& b);
// The capacity overrides applied on a params struct.
Status apply_board_capacity(const Board& b, Params* p);
// The udp endpoint "a.b.c.d:port" split; false when malformed.
bool split_endpoint(const char* endpoint, char* ip, int ip_size, uint16_t* port);

}  // namespace rgbdtam

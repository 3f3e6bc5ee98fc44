// Board definitions: the shipped boards load and validate; bad ones fail with errors that
// name the board, the file, the line and the key.
#include <gtest/gtest.h>

#include <dirent.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "config_text.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/runtime/board.hpp"
#include "run_job.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

Status load(const std::string& dir, Board* b) {
  char* text = nullptr;
  RGBDTAM_RETURN_IF_ERROR(read_text_file((dir + "/board.conf").c_str(), 1 << 16, &text));
  const Status s = parse_board(text, (dir + "/board.conf").c_str(), dir.c_str(), b);
  delete[] text;
  return s;
}

TEST(Board, ShippedBoardsLoadAndValidate) {
  for (const char* name : {"host-emulation", "raspberry-pi-4", "raspberry-pi-5", "radxa-rock-5b"}) {
    Board b;
    const Status s = load(testing::source_path(std::string("board/") + name), &b);
    ASSERT_TRUE(s.is_ok()) << s.message();
    EXPECT_STREQ(b.name, name);
    const Status v = validate_board(b);
    EXPECT_TRUE(v.is_ok()) << v.message();
    // The camera's optical axis is the body's forward axis on every shipped board.
    const Vector3d forward = b.T_b_c.rotation() * Vector3d(0, 0, 1);
    EXPECT_NEAR(forward.x(), 1.0, 1e-9) << name;
    // Their params files exist and the capacity overrides are valid params.
    char* text = nullptr;
    ASSERT_TRUE(read_text_file(b.sensor_config, 1 << 20, &text).is_ok()) << b.sensor_config;
    Params p;
    EXPECT_TRUE(parse_params(text, b.sensor_config, &p).is_ok());
    delete[] text;
    EXPECT_TRUE(apply_board_capacity(b, &p).is_ok());
  }
}

std::vector<std::string> shipped_boards() {
  std::vector<std::string> names;
  DIR* dir = opendir(testing::source_path("board").c_str());
  if (dir == nullptr) return names;
  while (const dirent* entry = readdir(dir)) {
    const std::string name = entry->d_name;
    std::ifstream conf(testing::source_path("board/" + name + "/board.conf"));
    if (name != "." && name != ".." && conf) names.push_back(name);
  }
  closedir(dir);
  return names;
}

// Each board's build.preset is a preset that names the board (RGBDTAM_BOARD), so that the
// board's own build runs BoardBuild.TheBoardsSensorIsInThisBuild (`rgbdtam check` on the board;
// tools/test.sh builds and tests each board's build).
TEST(Board, EveryBoardIsBuiltByAPresetThatNamesIt) {
  std::ifstream file(testing::source_path("CMakePresets.json"));
  std::stringstream presets;
  presets << file.rdbuf();
  const std::string json = presets.str();
  const std::vector<std::string> boards = shipped_boards();
  EXPECT_GE(boards.size(), 3u);
  for (const std::string& name : boards) {
    Board b;
    ASSERT_TRUE(load(testing::source_path("board/" + name), &b).is_ok()) << name;
    const size_t begin = json.find("\"name\": \"" + std::string(b.preset) + "\"");
    ASSERT_NE(begin, std::string::npos) << name << ": no preset " << b.preset;
    const size_t end = json.find("\"name\":", begin + 1);
    const std::string preset = json.substr(begin, end - begin);
    EXPECT_NE(preset.find("\"RGBDTAM_BOARD\": \"${sourceDir}/board/" + name + "\""),
              std::string::npos)
        << name << ": preset " << b.preset << " does not build for this board";
  }
}

TEST(Board, BackendsInThisBuildAreFoundByName) {
  EXPECT_TRUE(sensor_backend_in_build("replay"));
  EXPECT_TRUE(sensor_backend_in_build("v4l2"));
  EXPECT_FALSE(sensor_backend_in_build("repl"));
  EXPECT_FALSE(sensor_backend_in_build(""));
  EXPECT_FALSE(sensor_backend_in_build("kinect"));
}

TEST(Board, HostEmulationPathsAreRelativeToTheBoardFolder) {
  Board b;
  ASSERT_TRUE(load(testing::source_path("board/host-emulation"), &b).is_ok());
  char* text = nullptr;
  const std::string rgb = std::string(b.sensor_device) + "/rgb.txt";
  EXPECT_TRUE(read_text_file(rgb.c_str(), 1 << 20, &text).is_ok()) << rgb;
  delete[] text;
  ASSERT_TRUE(set_board_value("sensor.device=/elsewhere", &b).is_ok());
  EXPECT_STREQ(b.sensor_device, "/elsewhere");
  // An override's relative path means what it would in the board file.
  ASSERT_TRUE(set_board_value("sensor.device=../../data/tum_fr1_xyz_clip", &b).is_ok());
  EXPECT_EQ(std::string(b.sensor_device),
            testing::source_path("board/host-emulation") + "/../../data/tum_fr1_xyz_clip");
  ASSERT_TRUE(set_board_value("sensor.config = ../../config/tum_fr3.conf", &b).is_ok());
  EXPECT_EQ(std::string(b.sensor_config),
            testing::source_path("board/host-emulation") + "/../../config/tum_fr3.conf");
}

void expect_board_error(const std::string& text, const std::string& must_contain) {
  Board b;
  Status s = parse_board(text.c_str(), "bad.conf", "board/bad", &b);
  if (s.is_ok()) s = validate_board(b);
  ASSERT_FALSE(s.is_ok()) << "accepted: " << text;
  EXPECT_NE(std::string(s.message()).find(must_contain), std::string::npos) << s.message();
}

constexpr const char* kMinimalBoard =
    "board.name = bad\nbuild.preset = host-release\nboard.cpu_count = 2\nsensor.kind = replay\n"
    "sensor.device = x\nsensor.config = y\nlink.kind = udp\nlink.udp_remote = 127.0.0.1:14550\n";

TEST(Board, BadBoardsAreClearErrors) {
  Board ok;
  ASSERT_TRUE(parse_board(kMinimalBoard, "ok.conf", "board/ok", &ok).is_ok());
  ASSERT_TRUE(validate_board(ok).is_ok());
  expect_board_error("board.name = x\n", "missing required key 'build.preset'");
  expect_board_error(testing::with_changes(kMinimalBoard, "sensor.kind = kinect2\n"),
                     "sensor.kind 'kinect2'");
  expect_board_error(testing::with_changes(kMinimalBoard, "link.kind = can\n"), "link.kind 'can'");
  expect_board_error(testing::with_changes(kMinimalBoard, "link.udp_remote = 127.0.0.1\n"),
                     "link.udp_remote");
  expect_board_error(testing::with_changes(kMinimalBoard, "link.udp_remote = 127.0.0.1:70000\n"),
                     "link.udp_remote");
  expect_board_error(testing::with_changes(kMinimalBoard, "link.kind = serial\n"),
                     "link.serial_device");
  expect_board_error(testing::with_changes(kMinimalBoard, "link.baud = 50\n"),
                     "bad.conf:9: key 'link.baud'");
  expect_board_error(testing::with_changes(kMinimalBoard, "threads.mapper_cpu = 2\n"),
                     "threads.mapper_cpu is 2, but the board has 2 CPUs");
  expect_board_error(
      testing::with_changes(kMinimalBoard, "threads.tracker_cpu = 1\nthreads.builder_cpu = 1\n"),
      "threads.builder_cpu is the tracker's CPU (1)");
  expect_board_error(testing::with_changes(kMinimalBoard, "gpio.led_line = 3\n"),
                     "gpio.chip is empty");
  expect_board_error(testing::with_changes(kMinimalBoard, "link.T_b_c = 1 0 0\n"), "link.T_b_c");
  expect_board_error(testing::with_changes(kMinimalBoard, "link.T_b_c = 2 0 0 0 0 0 0\n"),
                     "link.T_b_c");
  expect_board_error(testing::with_changes(kMinimalBoard, "link.T_b_c = nan 0 0 0 0 0 0\n"),
                     "link.T_b_c");
  expect_board_error(testing::with_changes(kMinimalBoard, "link.T_b_c = 1 0 0 0 0 inf 0\n"),
                     "link.T_b_c");
  expect_board_error(testing::with_changes(kMinimalBoard, "threads.link_priority = 120\n"),
                     "out of range");
  expect_board_error(testing::with_changes(kMinimalBoard, "gpio.led_pin = 3\n"),
                     "unknown key 'gpio.led_pin'");
  expect_board_error(testing::with_changes(kMinimalBoard, "sensor.usb_id = kinect\n"),
                     "sensor.usb_id 'kinect'");
  expect_board_error(testing::with_changes(kMinimalBoard, "sensor.depth = metric\n"),
                     "sensor.depth 'metric'");
  expect_board_error(
      testing::with_changes(kMinimalBoard, "sensor.kind = v4l2\nsensor.device = usb\n"),
      "sensor.device = usb finds the camera's nodes by its USB id: set sensor.usb_id");
  expect_board_error(testing::with_changes(kMinimalBoard, "origin.latitude_deg = 47.4\n"),
                     "origin.latitude_deg and origin.longitude_deg go together");
  expect_board_error(testing::with_changes(kMinimalBoard, "origin.latitude_deg = 91\n"),
                     "out of range");
  expect_board_error(testing::with_changes(kMinimalBoard, "origin.latitude_deg = nan\n"),
                     "origin.latitude_deg");
  expect_board_error(testing::with_changes(kMinimalBoard, "autopilot.attitude_sigma = 0\n"),
                     "out of range");
}

TEST(Board, CapacityOverridesAreCheckedLikeParams) {
  Board b;
  ASSERT_TRUE(
      parse_board((testing::with_changes(kMinimalBoard, "capacity.keyframe_pool = 4\n")).c_str(),
                  "small.conf", "board/small", &b)
          .is_ok());
  Params p;
  const Status s = apply_board_capacity(b, &p);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("board 'bad'"), std::string::npos) << s.message();
  EXPECT_NE(std::string(s.message()).find("map.keyframe_pool"), std::string::npos);
}

TEST(Board, TheSmallBoardProfileTracksDownTo320x240WithTheBoardsPointBudget) {
  Board b;
  ASSERT_TRUE(parse_board(testing::with_changes(kMinimalBoard,
                                                "capacity.finest_tracked_level = 1\n"
                                                "capacity.photometric_points = 4000\n")
                              .c_str(),
                          "small.conf", "board/small", &b)
                  .is_ok());
  Params p;
  ASSERT_TRUE(apply_board_capacity(b, &p).is_ok());
  EXPECT_EQ(p.tracker.max_iterations[0], 0);
  EXPECT_GT(p.tracker.max_iterations[1], 0);
  EXPECT_EQ(p.tracker.photometric_points_finest, 4000);
  expect_board_error(testing::with_changes(kMinimalBoard, "capacity.finest_tracked_level = 2\n"),
                     "out of range");
}

TEST(Board, ABoardWithoutRoomForTheLocalWindowTurnsItOff) {
  Params p;
  ASSERT_TRUE(p.loop.window);
  Board keeps;
  ASSERT_TRUE(parse_board(kMinimalBoard, "keeps.conf", "board/keeps", &keeps).is_ok());
  ASSERT_TRUE(apply_board_capacity(keeps, &p).is_ok());
  EXPECT_TRUE(p.loop.window);
  Board small;
  ASSERT_TRUE(
      parse_board(testing::with_changes(kMinimalBoard, "capacity.local_window = false\n").c_str(),
                  "small.conf", "board/small", &small)
          .is_ok());
  ASSERT_TRUE(apply_board_capacity(small, &p).is_ok());
  EXPECT_FALSE(p.loop.window);
}

TEST(Board, EndpointsSplit) {
  char ip[32];
  uint16_t port = 0;
  EXPECT_TRUE(split_endpoint("192.168.1.2:14540", ip, sizeof(ip), &port));
  EXPECT_STREQ(ip, "192.168.1.2");
  EXPECT_EQ(port, 14540);
  EXPECT_FALSE(split_endpoint(":14540", ip, sizeof(ip), &port));
  EXPECT_FALSE(split_endpoint("1.2.3.4:", ip, sizeof(ip), &port));
  EXPECT_FALSE(split_endpoint("1.2.3.4:0", ip, sizeof(ip), &port));
  EXPECT_FALSE(split_endpoint("1.2.3.4:12x", ip, sizeof(ip), &port));
}

}  // namespace
}  // namespace rgbdtam

// Config files: the shipped ones load, and every kind of bad value is a clear error that
// names the file and the key.
#include <dirent.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "config_text.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

const char* kMinimal =
    "camera.width = 640\ncamera.height = 480\ncamera.fx = 500\ncamera.fy = 500\n"
    "camera.cx = 320\ncamera.cy = 240\ndepth.factor = 1000\n";

Status parse(const std::string& text, Params* p) {
  return parse_params(text.c_str(), "test.conf", p);
}

TEST(Params, EveryShippedConfigLoads) {
  std::vector<std::string> names;
  DIR* dir = ::opendir(testing::source_path("config").c_str());
  ASSERT_NE(dir, nullptr);
  while (const dirent* e = ::readdir(dir)) {
    const std::string name = e->d_name;
    if (name.size() > 5 && name.compare(name.size() - 5, 5, ".conf") == 0) names.push_back(name);
  }
  ::closedir(dir);
  EXPECT_GE(names.size(), 5u);
  for (const std::string& name : names) {
    char* text = nullptr;
    const std::string path = testing::source_path("config/" + name);
    ASSERT_TRUE(read_text_file(path.c_str(), 1 << 20, &text).is_ok()) << path;
    Params p;
    const Status s = parse_params(text, path.c_str(), &p);
    delete[] text;
    EXPECT_TRUE(s.is_ok()) << s.message();
  }
}

TEST(Params, ValuesAndDefaults) {
  Params p;
  ASSERT_TRUE(
      parse(testing::with_changes(kMinimal,
                                  "tracker.residuals = GIDD*  # comment\n"
                                  "tracker.motion_model = false\ndepth.max_rgb_dt_ms = 15\n"),
            &p)
          .is_ok());
  EXPECT_EQ(p.camera.fx_px, 500.0);
  EXPECT_EQ(p.sensor.depth_factor, 1000.0);
  EXPECT_FALSE(p.tracker.motion_model);
  EXPECT_EQ(p.sensor.max_rgb_depth_dt_ns, 15'000'000);
  EXPECT_EQ(p.tracker.residuals.photometric, PhotometricMode::kOff);
  EXPECT_EQ(p.tracker.residuals.sampling, GeometricSampling::kDense);
  EXPECT_EQ(p.keyframe_pool_size, Params().keyframe_pool_size);  // untouched keys keep defaults
}

void expect_error(const std::string& text, const char* must_contain) {
  Params p;
  const Params before = p;
  const Status s = parse(text, &p);
  ASSERT_FALSE(s.is_ok()) << text;
  const std::string msg = s.message();
  EXPECT_NE(msg.find("test.conf"), std::string::npos) << msg;
  EXPECT_NE(msg.find(must_contain), std::string::npos) << msg;
  EXPECT_EQ(p.camera.fx_px, before.camera.fx_px) << "a failed load must not change the params";
}

TEST(Params, BadValuesNameTheFileAndTheKey) {
  expect_error(testing::with_changes(kMinimal, "tracker.robust_cc = 2\n"),
               "unknown key 'tracker.robust_cc'");
  expect_error(testing::with_changes(kMinimal, "camera.fx =\n"), "'camera.fx' has no value");
  expect_error(testing::with_changes(kMinimal, "tracker.keyframe_overlap = 1.5\n"),
               "'tracker.keyframe_overlap'");
  expect_error(testing::with_changes(kMinimal, "tracker.keyframe_overlap = 1.5\n"), "out of range");
  expect_error(testing::with_changes(kMinimal, "camera.fx = five hundred\n"), "is not a number");
  expect_error(testing::with_changes(kMinimal, "map.keyframe_pool = 3.5\n"), "not a whole number");
  expect_error(testing::with_changes(kMinimal, "tracker.motion_model = maybe\n"), "true/false");
  expect_error(testing::with_changes(kMinimal, "tracker.residuals = PX+GIDD\n"),
               "'PX+GIDD' is not valid (PS, PD");
  expect_error(testing::with_changes(kMinimal, "just some words\n"), "expected 'key = value'");
  expect_error("camera.width = 640\n", "missing required key");
  expect_error(testing::with_changes(kMinimal, "camera.width = 636\n"), "divisible by 8");
  expect_error(testing::with_changes(kMinimal, "depth.min = 4\ndepth.max = 2\n"), "'depth.min'");
  expect_error(testing::with_changes(kMinimal, "camera.fx = nan\n"), "is not a number");
  expect_error(testing::with_changes(kMinimal, "map.enabled = true\nmap.keyframe_pool = 6\n"),
               "'map.keyframe_pool'");
}

// Issue 36: a depth camera of its own, registered in software.
const char* kDepthCamera =
    "depth_camera.fx = 420\ndepth_camera.fy = 421\ndepth_camera.cx = 318\n"
    "depth_camera.cy = 241\ndepth_camera.k1 = -0.05\n"
    "depth_camera.T_c_d = 1 0 0 0 -0.015 0 0\ndepth_camera.register = true\n";

TEST(Params, ADepthCameraOfItsOwnIsReadAndAnIncompleteOneRefused) {
  Params p;
  ASSERT_TRUE(parse(testing::with_changes(kMinimal, kDepthCamera), &p).is_ok());
  EXPECT_TRUE(p.depth_camera.register_to_colour);
  EXPECT_EQ(p.depth_camera.intrinsics.fy_px, 421.0);
  EXPECT_EQ(p.depth_camera.distortion.k1, -0.05);
  EXPECT_NEAR(p.depth_camera.T_c_d.translation().x(), -0.015, 1e-12);
  expect_error(testing::with_changes(kMinimal, "depth_camera.register = true\n"),
               "needs the depth camera's 'depth_camera.fx'");
  expect_error(
      testing::with_changes(kMinimal,
                            "depth_camera.fx = 420\ndepth_camera.fy = 421\ndepth_camera.T_c_d = 1 "
                            "0 0 0 1.5 0 0\ndepth_camera.register = true\n"),
      "translation in metres, not mm?");
  expect_error(testing::with_changes(kMinimal, "depth_camera.T_c_d = 2 0 0 0 0 0 0\n"),
               "'depth_camera.T_c_d'");
}

TEST(Params, TheDepthImageIsColoursSizeUnlessItsCameraGivesItsOwn) {
  const std::string depth_camera = kDepthCamera;
  Params p;
  ASSERT_TRUE(parse(testing::with_changes(kMinimal, depth_camera), &p).is_ok());
  SensorImageSize size = sensor_image_size(p);
  EXPECT_EQ(size.depth_width_px, p.camera.width_px);
  EXPECT_EQ(size.depth_height_px, p.camera.height_px);
  ASSERT_TRUE(parse(testing::with_changes(kMinimal, depth_camera + "depth_camera.width = 848\n"
                                                                   "depth_camera.height = 480\n"),
                    &p)
                  .is_ok());
  size = sensor_image_size(p);
  EXPECT_EQ(size.width_px, p.camera.width_px);
  EXPECT_EQ(size.depth_width_px, 848);
  EXPECT_EQ(size.depth_height_px, 480);
  expect_error(testing::with_changes(kMinimal, depth_camera + "depth_camera.width = 848\n"),
               "both or neither");
  // Depth the device registers is colour's size.
  expect_error(testing::with_changes(kMinimal,
                                     "depth_camera.width = 848\ndepth_camera.height = "
                                     "480\n"),
               "only with 'depth_camera.register = true'");
}

TEST(Params, HealthLimitsAreReadInTheirUnits) {
  Params p;
  ASSERT_TRUE(
      parse(testing::with_changes(kMinimal,
                                  "health.max_rotation_rate = 180\nhealth.max_speed = 2\n"
                                  "health.max_rotation_std = 1\nhealth.reset_after_lost_ms = 250\n"
                                  "tracker.keyframe_parallax = 0.2\n"),
            &p)
          .is_ok());
  EXPECT_DOUBLE_EQ(p.health.max_rotation_rate_rad_s, M_PI);  // written in degrees per second
  EXPECT_DOUBLE_EQ(p.health.max_rotation_std_rad, M_PI / 180.0);
  EXPECT_EQ(p.health.max_speed_m_s, 2.0);
  EXPECT_EQ(p.reset_after_lost_ns, 250'000'000);
  EXPECT_EQ(p.tracker.keyframe_parallax, 0.2);
  expect_error(testing::with_changes(kMinimal, "health.min_inliers = 1.5\n"), "out of range");
  expect_error(testing::with_changes(kMinimal, "health.max_speed = inf\n"), "is not a number");
  // Keys that were replaced are errors, not silently ignored.
  expect_error(testing::with_changes(kMinimal, "tracker.lost_frames_before_reset = 10\n"),
               "unknown key 'tracker.lost_frames_before_reset'");
}

TEST(Params, ErrorsGiveTheLineNumber) {
  Params p;
  const Status s = parse(testing::with_changes(kMinimal, "\n# fine\nbogus = 1\n"), &p);
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("test.conf:10"), std::string::npos) << s.message();
}

TEST(Params, AnyLineEndingsLongCommentsAndNoKeyTwice) {
  Params p;
  std::string cr_only = testing::with_changes(kMinimal, "camera.fx = 525\n");
  for (char& c : cr_only) c = c == '\n' ? '\r' : c;
  ASSERT_TRUE(parse(cr_only, &p).is_ok()) << "old Mac line endings";
  EXPECT_EQ(p.camera.fx_px, 525.0);
  ASSERT_TRUE(parse("# " + std::string(600, '-') + "\r\n" + kMinimal, &p).is_ok())
      << "a comment of any length, CRLF endings";
  const Status twice = parse(std::string(kMinimal) + "camera.fx = 525\n", &p);
  ASSERT_FALSE(twice.is_ok());
  EXPECT_NE(std::string(twice.message()).find("test.conf:8: key 'camera.fx' is given a second"),
            std::string::npos)
      << twice.message();
  expect_error(std::string(kMinimal) + "camera.cx = 3" + std::string(600, '0') + "\n",
               "test.conf:8: line longer than");
  expect_error(std::string(kMinimal) + "\x7f" + "ELF\x02\x01\n",
               "test.conf:8: not text (control byte 0x7f");
}

TEST(Params, OverridesAndPrintRoundTrip) {
  Params p;
  ASSERT_TRUE(parse(kMinimal, &p).is_ok());
  ASSERT_TRUE(set_param("tracker.robust_c=3.5", "--set", &p).is_ok());
  EXPECT_EQ(p.tracker.robust_c, 3.5);
  EXPECT_FALSE(set_param("tracker.robust_c=-1", "--set", &p).is_ok());
  EXPECT_EQ(p.tracker.robust_c, 3.5);
  static char printed[16384];
  print_params(p, printed, sizeof(printed));
  Params q;
  ASSERT_TRUE(parse_params(printed, "printed", &q).is_ok());
  static char again[16384];
  print_params(q, again, sizeof(again));
  EXPECT_STREQ(printed, again);
}

TEST(ResidualConfig, ParsesEveryAblationName) {
  for (const char* name : {"PS", "PD", "GIDS", "GIDD", "GIDD*", "PS+GIDD", "PS+GDD", "PD+GIDD*"}) {
    ResidualConfig c;
    ASSERT_TRUE(ResidualConfig::parse(name, &c)) << name;
    char back[16];
    c.name(back, sizeof(back));
    EXPECT_STREQ(back, name);
  }
  ResidualConfig c;
  for (const char* bad : {"", "P", "GID", "PS+", "+GIDD", "PS+PD", "GIDDD", "ps"}) {
    EXPECT_FALSE(ResidualConfig::parse(bad, &c)) << bad;
  }
}

}  // namespace
}  // namespace rgbdtam

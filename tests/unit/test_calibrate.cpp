// The calibration tool (tools/calibrate) on checkerboard views rendered into two cameras of
// known intrinsics, distortion and relative pose, as a D435's colour and depth cameras are:
// every value must come back within 0.5 % (focal lengths, principal points) and 1 mm.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "calibration.hpp"
#include "rgbdtam/runtime/params.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

struct Camera {
  cv::Matx33d K;
  cv::Vec<double, 5> distortion;
  cv::Size size;
};

// Each pixel's ray (x, y, 1) through 3x3 sample points, from the distorted image to the normalised
// plane: computed once per camera.
std::vector<cv::Point2f> pixel_rays(const Camera& c, int samples) {
  std::vector<cv::Point2f> at;
  for (int v = 0; v < c.size.height; ++v) {
    for (int u = 0; u < c.size.width; ++u) {
      for (int sy = 0; sy < samples; ++sy) {
        for (int sx = 0; sx < samples; ++sx) {
          at.emplace_back(u - 0.5f + (sx + 0.5f) / samples, v - 0.5f + (sy + 0.5f) / samples);
        }
      }
    }
  }
  std::vector<cv::Point2f> rays;
  cv::undistortPoints(at, rays, cv::Mat(c.K), cv::Mat(c.distortion));
  return rays;
}

// The board (inner corners cols x rows, side s, corner (0, 0) at the board frame's origin, a
// white margin of one square) seen by the camera at T_cam_board, on a mid-grey background.
cv::Mat render(const Camera& c, const std::vector<cv::Point2f>& rays, int samples,
               const cv::Matx33d& R, const cv::Vec3d& t, const Checkerboard& b) {
  cv::Mat image(c.size, CV_8U);
  const cv::Vec3d normal(R(0, 2), R(1, 2), R(2, 2));
  const cv::Matx33d R_b_c = R.t();
  const double n_dot_t = normal.dot(t);
  const double s = b.square_m;
  const int n = samples * samples;
  for (int p = 0; p < c.size.area(); ++p) {
    double sum = 0;
    for (int k = 0; k < n; ++k) {
      const cv::Point2f& r = rays[static_cast<size_t>(p) * n + k];
      const cv::Vec3d ray(r.x, r.y, 1.0);
      const double lambda = n_dot_t / normal.dot(ray);
      double value = 128;
      if (lambda > 0) {
        const cv::Vec3d on_board = R_b_c * (ray * lambda - t);
        const double x = on_board[0] / s, y = on_board[1] / s;
        const bool checker =
            x >= -1 && y >= -1 && x < b.inner_corners.width && y < b.inner_corners.height;
        const bool margin =
            x >= -2 && y >= -2 && x < b.inner_corners.width + 1 && y < b.inner_corners.height + 1;
        if (checker) {
          value =
              ((static_cast<int>(std::floor(x)) + static_cast<int>(std::floor(y))) & 1) ? 220 : 30;
        } else if (margin) {
          value = 220;
        }
      }
      sum += value;
    }
    image.data[p] = static_cast<uint8_t>(std::lround(sum / n));
  }
  return image;
}

cv::Matx33d rotation(double rx_deg, double ry_deg, double rz_deg) {
  cv::Mat R;
  cv::Rodrigues(cv::Vec3d(rx_deg, ry_deg, rz_deg) * (M_PI / 180.0), R);
  return cv::Matx33d(R);
}

struct Rig {
  // A D435's cameras at 640x480 (config/realsense_d435.conf), the colour one with some
  // distortion, and a turn between them of about half a degree.
  Camera colour{
      {612.4, 0, 314.3, 0, 610.6, 237.8, 0, 0, 1}, {0.08, -0.15, 0.001, -0.0005, 0}, {640, 480}};
  Camera depth{{385.1, 0, 321.6, 0, 385.1, 241.6, 0, 0, 1}, {0, 0, 0, 0, 0}, {640, 480}};
  cv::Matx33d R_c_d = rotation(0.2, -0.3, 0.5);
  cv::Vec3d t_c_d{0.0150, -0.0014, 0.0002};
  Checkerboard board{{9, 6}, 0.04};
  std::vector<cv::Mat> colour_views, depth_views;
  Rig() {
    constexpr int kSamples = 3;
    const std::vector<cv::Point2f> colour_rays = pixel_rays(colour, kSamples);
    const std::vector<cv::Point2f> depth_rays = pixel_rays(depth, kSamples);
    // The board 0.55-0.85 m away, turned up to 30 degrees, across the colour camera's image.
    // With 14 views instead of 20 the baseline came back 0.7-1.0 mm off.
    for (int i = 0; i < 20; ++i) {
      const double a = i * 0.7;
      const cv::Matx33d R =
          rotation(25 * std::sin(a), 25 * std::cos(1.3 * a), 10 * std::sin(2 * a));
      // The board's centre on the colour camera's axis, shifted a little.
      const cv::Vec3d centre(0.06 * std::cos(a), 0.04 * std::sin(1.7 * a), 0.55 + 0.015 * i);
      const cv::Vec3d half(board.square_m * (board.inner_corners.width - 1) / 2,
                           board.square_m * (board.inner_corners.height - 1) / 2, 0);
      const cv::Vec3d t_c_b = centre - R * half;
      colour_views.push_back(render(colour, colour_rays, kSamples, R, t_c_b, board));
      // The depth camera's view: T_d_b = T_c_d^-1 T_c_b.
      const cv::Matx33d R_d_c = R_c_d.t();
      depth_views.push_back(
          render(depth, depth_rays, kSamples, R_d_c * R, R_d_c * (t_c_b - t_c_d), board));
    }
  }
};

const Rig& rig() {
  static const Rig r;  // rendering takes a few seconds: once for the suite
  return r;
}

void expect_intrinsics(const CameraCalibration& got, const Camera& truth, const char* which) {
  for (const auto& [row, col] : {std::pair{0, 0}, {1, 1}, {0, 2}, {1, 2}}) {
    const double want = truth.K(row, col);
    EXPECT_NEAR(got.K(row, col), want, 0.005 * want) << which << " K(" << row << "," << col << ")";
  }
  EXPECT_LT(got.rms_px, 0.2) << which;
}

TEST(Calibration, RenderedViewsGiveBackBothCamerasAndTheirPoseWithinHalfAPercentAndAMillimetre) {
  const Rig& r = rig();
  RgbdCalibration c;
  std::string error;
  ASSERT_TRUE(calibrate_rgbd(r.colour_views, r.depth_views, r.board, 8, &c, &error)) << error;
  EXPECT_EQ(c.views, 20);
  expect_intrinsics(c.colour, r.colour, "colour");
  expect_intrinsics(c.depth, r.depth, "depth camera");
  EXPECT_NEAR(c.colour.distortion[0], 0.08, 0.01);
  EXPECT_NEAR(c.colour.distortion[1], -0.15, 0.05);
  EXPECT_LT(cv::norm(c.t_c_d - r.t_c_d), 0.001) << c.t_c_d;
  cv::Vec3d turn;
  cv::Rodrigues(cv::Mat(c.R_c_d * r.R_c_d.t()), turn);
  EXPECT_LT(cv::norm(turn) * 180 / M_PI, 0.1) << "degrees off";
  std::printf(
      "calibration: %d views; colour fx %.2f (true %.2f) cx %.2f (%.2f), depth fx %.2f "
      "(%.2f); baseline off by %.2f mm, turn by %.3f deg; RMS %.3f / %.3f / %.3f px\n",
      c.views, c.colour.K(0, 0), r.colour.K(0, 0), c.colour.K(0, 2), r.colour.K(0, 2),
      c.depth.K(0, 0), r.depth.K(0, 0), 1e3 * cv::norm(c.t_c_d - r.t_c_d),
      cv::norm(turn) * 180 / M_PI, c.colour.rms_px, c.depth.rms_px, c.stereo_rms_px);

  // The keys it writes are a valid camera config that registers depth.
  const std::string keys =
      "camera.width = 640\ncamera.height = 480\ndepth.factor = 1000\n" + config_keys(c);
  Params p;
  const Status s = parse_params(keys.c_str(), "calibrated.conf", &p);
  ASSERT_TRUE(s.is_ok()) << s.message() << "\n" << keys;
  EXPECT_TRUE(p.depth_camera.register_to_colour);
  EXPECT_NEAR(p.depth_camera.intrinsics.fx_px, 385.1, 0.005 * 385.1);
  EXPECT_EQ(sensor_image_size(p).depth_width_px, 640) << "the infrared image's size";
  EXPECT_EQ(sensor_image_size(p).depth_height_px, 480);
  EXPECT_NEAR(p.depth_camera.T_c_d.translation().x(), 0.0150, 0.001);
  EXPECT_NEAR(p.distortion.k1, 0.08, 0.01);
}

TEST(Calibration, TooFewViewsWhereBothCamerasSeeTheBoardIsAClearError) {
  const Rig& r = rig();
  std::vector<cv::Mat> colour(r.colour_views.begin(), r.colour_views.begin() + 4);
  std::vector<cv::Mat> depth(r.depth_views.begin(), r.depth_views.begin() + 4);
  depth[1] = cv::Mat(depth[1].size(), CV_8U, cv::Scalar(128));  // the depth camera saw nothing
  RgbdCalibration c;
  std::string error;
  EXPECT_FALSE(calibrate_rgbd(colour, depth, r.board, 8, &c, &error));
  EXPECT_EQ(error.rfind("the board was found by both cameras in 3 of 4 pairs; at least 8", 0), 0u)
      << error;
  depth.pop_back();
  EXPECT_FALSE(calibrate_rgbd(colour, depth, r.board, 3, &c, &error));
  EXPECT_NE(error.find("must come in pairs (4 and 3)"), std::string::npos) << error;
}

#ifdef RGBDTAM_CALIBRATE_BINARY
TEST(Calibration, TheToolReadsFoldersOfViewsAndWritesTheKeysToANewFile) {
  const Rig& r = rig();
  const std::string dir = testing::make_temp_dir("calibrate");
  ::mkdir((dir + "/colour").c_str(), 0755);
  ::mkdir((dir + "/ir").c_str(), 0755);
  for (size_t i = 0; i < r.colour_views.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "/%02zu.png", i);
    ASSERT_TRUE(cv::imwrite(dir + "/colour" + name, r.colour_views[i]));
    ASSERT_TRUE(cv::imwrite(dir + "/ir" + name, r.depth_views[i]));
  }
  const std::string tool = RGBDTAM_CALIBRATE_BINARY;
  const std::string args = " " + dir + "/colour " + dir + "/ir --board 9x6 --square-m 0.04";
  EXPECT_EQ(std::system((tool + args + " --out " + dir + "/d435.conf >/dev/null").c_str()), 0);
  std::ifstream file(dir + "/d435.conf");
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("depth_camera.T_c_d = "), std::string::npos) << text;
  // It writes no file over another, and refuses millimetres for metres.
  EXPECT_NE(std::system((tool + args + " --out " + dir + "/d435.conf 2>/dev/null").c_str()), 0);
  EXPECT_NE(std::system(
                (tool + " " + dir + "/colour " + dir + "/ir --board 9x6 --square-m 40 2>/dev/null")
                    .c_str()),
            0);
}
#endif

}  // namespace
}  // namespace rgbdtam

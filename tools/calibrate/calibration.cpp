#include "calibration.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>

#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/runtime/key_value.hpp"

namespace rgbdtam {
namespace {

std::vector<cv::Point3f> board_points(const Checkerboard& board) {
  std::vector<cv::Point3f> points;
  for (int r = 0; r < board.inner_corners.height; ++r) {
    for (int c = 0; c < board.inner_corners.width; ++c) {
      points.emplace_back(static_cast<float>(c * board.square_m),
                          static_cast<float>(r * board.square_m), 0.f);
    }
  }
  return points;
}

CameraCalibration calibrate_one(const std::vector<std::vector<cv::Point3f>>& object,
                                const std::vector<std::vector<cv::Point2f>>& image, cv::Size size) {
  CameraCalibration c;
  cv::Mat K, distortion;
  std::vector<cv::Mat> rvecs, tvecs;
  c.rms_px = cv::calibrateCamera(object, image, size, K, distortion, rvecs, tvecs);
  c.K = cv::Matx33d(K);
  for (int i = 0; i < 5; ++i) c.distortion[i] = distortion.at<double>(i);
  return c;
}

}  // namespace

bool find_corners(const cv::Mat& gray, const Checkerboard& board, std::vector<cv::Point2f>* out) {
  out->clear();
  if (!cv::findChessboardCorners(gray, board.inner_corners, *out,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
    return false;
  }
  cv::cornerSubPix(gray, *out, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
  return true;
}

bool calibrate_rgbd(const std::vector<cv::Mat>& colour, const std::vector<cv::Mat>& depth_ir,
                    const Checkerboard& board, int min_views, RgbdCalibration* out,
                    std::string* error) {
  if (colour.size() != depth_ir.size() || colour.empty()) {
    *error = "the colour and depth camera views must come in pairs (" +
             std::to_string(colour.size()) + " and " + std::to_string(depth_ir.size()) + ")";
    return false;
  }
  const std::vector<cv::Point3f> points = board_points(board);
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> in_colour, in_depth;
  for (size_t i = 0; i < colour.size(); ++i) {
    std::vector<cv::Point2f> c, d;
    if (find_corners(colour[i], board, &c) && find_corners(depth_ir[i], board, &d)) {
      object.push_back(points);
      in_colour.push_back(c);
      in_depth.push_back(d);
    }
  }
  out->views = static_cast<int>(object.size());
  if (out->views < min_views) {
    *error = "the board was found by both cameras in " + std::to_string(out->views) + " of " +
             std::to_string(colour.size()) + " pairs; at least " + std::to_string(min_views) +
             " are needed (tilt it, fill the image with it, keep it still while both capture)";
    return false;
  }
  out->colour = calibrate_one(object, in_colour, colour[0].size());
  out->depth = calibrate_one(object, in_depth, depth_ir[0].size());
  out->depth_size = depth_ir[0].size();
  // Each camera's intrinsics as calibrated alone; the stereo step finds only the extrinsics.
  cv::Mat K_d(out->depth.K), K_c(out->colour.K);
  cv::Mat dist_d(out->depth.distortion), dist_c(out->colour.distortion);
  cv::Mat R, T, E, F;
  out->stereo_rms_px = cv::stereoCalibrate(object, in_depth, in_colour, K_d, dist_d, K_c, dist_c,
                                           colour[0].size(), R, T, E, F, cv::CALIB_FIX_INTRINSIC);
  out->R_c_d = cv::Matx33d(R);
  out->t_c_d = cv::Vec3d(T);
  return true;
}

std::string config_keys(const RgbdCalibration& c) {
  char text[2048];
  // The pose as the params file's parser reads it.
  Matrix3d R;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) R(r, k) = c.R_c_d(r, k);
  }
  const SE3 T_c_d(Eigen::Quaterniond(R), Vector3d(c.t_c_d[0], c.t_c_d[1], c.t_c_d[2]));
  char pose[160];
  print_pose_value(&T_c_d, pose, sizeof(pose));
  const CameraCalibration& k = c.colour;
  const CameraCalibration& d = c.depth;
  std::snprintf(
      text, sizeof(text),
      "# rgbdtam-calibrate: %d views; reprojection RMS colour %.3f px, depth camera %.3f px, "
      "both %.3f px\n"
      "camera.fx = %.3f\ncamera.fy = %.3f\ncamera.cx = %.3f\ncamera.cy = %.3f\n"
      "camera.k1 = %.6f\ncamera.k2 = %.6f\ncamera.p1 = %.6f\ncamera.p2 = %.6f\ncamera.k3 = %.6f\n"
      "depth_camera.width = %d\ndepth_camera.height = %d\n"
      "depth_camera.fx = %.3f\ndepth_camera.fy = %.3f\ndepth_camera.cx = %.3f\n"
      "depth_camera.cy = %.3f\ndepth_camera.k1 = %.6f\ndepth_camera.k2 = %.6f\n"
      "depth_camera.p1 = %.6f\ndepth_camera.p2 = %.6f\ndepth_camera.k3 = %.6f\n"
      "depth_camera.T_c_d = %s\n"
      "depth_camera.register = true\n",
      c.views, k.rms_px, d.rms_px, c.stereo_rms_px, k.K(0, 0), k.K(1, 1), k.K(0, 2), k.K(1, 2),
      k.distortion[0], k.distortion[1], k.distortion[2], k.distortion[3], k.distortion[4],
      c.depth_size.width, c.depth_size.height, d.K(0, 0), d.K(1, 1), d.K(0, 2), d.K(1, 2),
      d.distortion[0], d.distortion[1], d.distortion[2], d.distortion[3], d.distortion[4], pose);
  return text;
}

}  // namespace rgbdtam

#pragma once
// Per-unit calibration of an RGB-D camera whose depth comes from a camera of its own (RealSense
// D4xx, Orbbec over UVC): OpenCV's calib3d on checkerboard views seen by the colour camera and by
// the depth camera (its infrared image, pixel-aligned with its depth), giving each camera's
// intrinsics and distortion and the depth camera's pose in the colour camera's frame, written as
// the camera config's keys. Host tool: allocates freely.

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace rgbdtam {

struct Checkerboard {
  cv::Size inner_corners;  // columns x rows of inner corners
  double square_m = 0.0;
};

struct CameraCalibration {
  cv::Matx33d K;
  cv::Vec<double, 5> distortion;  // k1 k2 p1 p2 k3 (OpenCV's order and model, and ours)
  double rms_px = 0.0;            // reprojection error over the views it saw
};

struct RgbdCalibration {
  CameraCalibration colour, depth;
  cv::Size depth_size;  // the depth camera's image (a D4xx's may differ from colour's)
  cv::Matx33d R_c_d;    // colour camera from depth camera
  cv::Vec3d t_c_d;      // metres
  double stereo_rms_px = 0.0;
  int views = 0;  // views where both cameras found the board
};

// Inner corners of the board in one grey image; false when not all were found.
bool find_corners(const cv::Mat& gray, const Checkerboard& board, std::vector<cv::Point2f>* out);

// Calibrates from pairs of views (colour[i] and depth_ir[i] taken together, the board still).
// Pairs where either camera misses the board are left out; at least `min_views` must remain.
bool calibrate_rgbd(const std::vector<cv::Mat>& colour, const std::vector<cv::Mat>& depth_ir,
                    const Checkerboard& board, int min_views, RgbdCalibration* out,
                    std::string* error);

// The camera config's keys (camera.*, depth_camera.*), with the errors as a comment.
std::string config_keys(const RgbdCalibration& c);

}  // namespace rgbdtam

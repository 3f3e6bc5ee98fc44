#pragma once
// Obstacle distances around the body from one depth image, for an autopilot's proximity
// avoidance (MAVLink OBSTACLE_DISTANCE): a horizontal field of view in front of the body is cut
// into 72 sectors of equal angle, and each holds the nearest horizontal distance of a depth
// point whose height lies in a band. It needs no pose, so it goes out whether or not tracking
// is valid. Body frame FRD (x forward, y right, z down), so bearings are clockwise from forward
// seen from above, as OBSTACLE_DISTANCE's angles are. The depth image is used as the sensor
// gives it (lens distortion is not removed: a Kinect's moves a bearing by a fraction of a
// sector).

#include <cstdint>

#include "rgbdtam/core/camera.hpp"
#include "rgbdtam/core/pyramid.hpp"
#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

struct ObstacleSectors {
  static constexpr int kCount = 72;
  static constexpr uint16_t kUnknown = UINT16_MAX;  // no depth in the sector
  // Nearest obstacle in cm; max_cm + 1 where depth was seen and none lay in the band; min_cm
  // for a surface nearer than the sensor's minimum (a reading below it, or BlindedSectors).
  uint16_t distance_cm[kCount] = {};
  float increment_deg = 0;     // each sector's width
  float angle_offset_deg = 0;  // sector 0's centre, from forward, clockwise positive
  uint16_t min_cm = 0, max_cm = 0;
};

struct ObstacleOptions {
  // Heights above the body's origin (m, up positive) whose points are obstacles.
  double lowest_m = -0.5, highest_m = 0.5;
  double fov_deg = 0;  // the sectors' span; 0: the camera's horizontal field of view
  int stride_px = 4;   // every stride-th pixel of every stride-th row
};

// A structured-light sensor sees nothing nearer than its minimum: a surface closer than that
// blinds it, and the sectors it fills have no depth, as sectors with nothing in range have. The
// two differ in what came before: an obstacle does not vanish between two reports, so a sector
// whose nearest obstacle was last within reach of the minimum (the minimum plus how far the
// camera can have moved since: health.max_speed times the time between the reports) and that
// now has no depth is blinded, and reads min_cm ("practically touching") until it has depth
// again. A sector without depth from the start, or last seen further, stays unknown.
class BlindedSectors {
 public:
  void init(double max_speed_m_s) { max_speed_m_s_ = max_speed_m_s; }
  // The report measured dt_s after the last one, marked where blinded; remembered for the next.
  void mark(double dt_s, ObstacleSectors* sectors);
  void forget();  // the next report starts without a past (a recording started again)

 private:
  double max_speed_m_s_ = 0.0;
  uint16_t last_cm_[ObstacleSectors::kCount] = {};  // 0: no report yet
};

class ObstacleSectorizer {
 public:
  // camera: the depth image's (registered to colour); T_b_c: body from camera.
  void init(const PinholeIntrinsics& camera, const SE3& T_b_c, double depth_factor,
            const DepthRange& range, const ObstacleOptions& options);
  void measure(const uint16_t* depth, ObstacleSectors* out) const;
  // The span the sectors cover (the camera's horizontal field of view when not configured).
  double fov_deg() const { return fov_deg_; }

 private:
  PinholeIntrinsics camera_;
  Eigen::Matrix3f R_b_c_;
  Eigen::Vector3f t_b_c_;
  float metres_per_unit_ = 0, min_m_ = 0, max_m_ = 0;
  float lowest_m_ = 0, highest_m_ = 0;
  double fov_deg_ = 0;
  int stride_ = 4;
};

}  // namespace rgbdtam

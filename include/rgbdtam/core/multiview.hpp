#pragma once
// Multi-view inverse depth for a keyframe's high-gradient (Canny) pixels (paper sec. V):
// a 1-D patch searched along the epipolar line of each later frame, refined to sub-pixel, with
// the uncertainty of one pixel of disparity; then inverse-variance fusion of the observations
// and of the sensor's own inverse depth. Keyframes are never fused with each other.

#include <cstdint>

#include "rgbdtam/core/camera.hpp"
#include "rgbdtam/core/fixed_vector.hpp"
#include "rgbdtam/core/se3.hpp"

namespace rgbdtam {

struct MultiViewOptions {
  int max_seeds = 10000;        // edge pixels mapped per keyframe
  int max_observations = 12;    // per seed
  int min_observations = 3;     // for a multi-view estimate
  float min_gradient = 0.028f;  // |gx|+|gy| per pixel in [0,1] units (7 grey levels; code)
  int border_px = 12;
  float max_mean_sad = 25.f;        // grey levels per patch sample (code)
  float min_parallax = 0.005f;      // |baseline * rho|: below it the ray angle is too small (code)
  float min_alignment = 0.3f;       // |gradient . epipolar| of unit vectors (code)
  float max_search_px = 160.f;      // longer epipolar segments are skipped (rows / 3; code)
  float max_inverse_depth = 4.f;    // 1/m: nearest depth 0.25 m, when the sensor sees nothing
  float min_inverse_depth = 0.02f;  // 1/m: farthest depth 50 m
  float consistency_sigmas = 2.f;   // an observation agrees within this many sigmas
  // A multi-view estimate enters the map when sigma_rho / rho is below max_relative_sigma, and
  // the tracker's points only below tracking_relative_sigma. Tracking errors feed back into
  // the next keyframes' triangulation: on the synthetic far wall, tracking on estimates up to
  // 4 % moved keyframes 1-2 enough to bias their whole wall by 5-6 %; at 3 % all stay under 1 %.
  float max_relative_sigma = 0.05f;
  float tracking_relative_sigma = 0.03f;
  bool usable_for_tracking(float rho, float sigma) const {
    return sigma <= tracking_relative_sigma * rho;
  }
};

enum class DepthSource : uint8_t { kNone = 0, kSensor = 1, kMultiView = 2, kFused = 3 };

struct FusedPixel {
  int16_t x, y;     // level-0 pixel
  float rho;        // 1/m
  float sigma;      // 1/m
  float intensity;  // [0,1]
  DepthSource source;
};

class SeedMap {
 public:
  void allocate(const PinholeIntrinsics& k, const MultiViewOptions& opt);
  // What allocate reserves, in bytes.
  static size_t bytes_needed(const MultiViewOptions& opt);
  // Starts mapping a keyframe: its undistorted grey image and sensor inverse depth (0 = none)
  // at level 0, its Canny edges, and its pose. The images must outlive the mapping. Seeds are
  // searched up to max_inverse_depth (1/m): half the depth of the nearest thing the keyframe
  // sees, as in the authors' code, so that the first epipolar segments stay short.
  void reset(const ImageF& gray, const ImageF& sensor_inverse_depth, const ImageU8& edges,
             const SE3& T_w_k, float max_inverse_depth);
  // Searches every seed along its epipolar line in a later frame; returns accepted observations.
  int observe(const ImageF& gray, const SE3& T_w_c);
  // Inverse-variance fusion of each seed's consistent observations with the sensor depth
  // (sigma_sensor in 1/m). Writes one FusedPixel per edge pixel that has any depth.
  void fuse(float sigma_sensor, FixedVector<FusedPixel>* out) const;

  int seed_count() const { return seeds_.size(); }
  const SE3& T_w_k() const { return T_w_k_; }

 private:
  struct Seed {
    int16_t x, y;
    float gx, gy;          // unit image gradient
    float rho_lo, rho_hi;  // current search interval, 1/m
    float sensor_rho;      // 0 when the sensor has none
    int16_t count;         // observations in this seed's slots of observations_
  };
  struct Observation {
    float rho, sigma;
  };
  // A frame's pose relative to the keyframe, once per frame rather than per seed.
  struct Motion {
    Eigen::Matrix3f R_c_k;
    Eigen::Vector3f t_c_k;
    Eigen::Vector3f centre_k;  // the frame's camera centre in the keyframe
  };
  Motion motion_to(const SE3& T_w_c) const;
  bool search(const Seed& s, const ImageF& gray, const Motion& m, Observation* out) const;

  MultiViewOptions opt_;
  PinholeIntrinsics k_;
  FixedVector<Seed> seeds_;
  FixedVector<Observation> observations_;  // max_observations slots per seed
  const ImageF* gray_ = nullptr;
  SE3 T_w_k_;
};

}  // namespace rgbdtam

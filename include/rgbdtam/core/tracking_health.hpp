#pragma once
// Whether a tracked pose may be reported as valid. Every check has a meaning of its own, so that
// a limit can be set from what it means rather than from a sequence it happens to fit.

#include <cstdint>

#include "rgbdtam/core/tracker.hpp"

namespace rgbdtam {

struct HealthLimits {
  int min_residuals = 100;
  // A term fits when its residual spread over the spread of what it compares is below this (1:
  // the alignment explains nothing; an unrelated image gives sqrt(2)) ...
  double max_agreement = 1.0;
  // ... and at least this fraction of its valid residuals is within 3 reference sigmas.
  double min_inliers = 0.7;
  // The photometric scale against its typical value over healthy frames.
  double max_sigma_ratio = 4.0;
  // One standard deviation along the worst direction: a tenth of the false-valid limits
  // (10 cm, 5 degrees), beyond which the data do not determine the pose.
  double max_translation_std_m = 0.01;
  double max_rotation_std_rad = 0.5 * 3.14159265358979 / 180.0;
  // Where the depth leaves a direction nearly free (planes sliding along planes), the image
  // alone must determine it: its reported standard deviation (covariance_scale applied) at most
  // a tenth of the false-valid tolerance, as above.
  double max_weak_direction_std_m = 0.01;
  double covariance_scale = 1.0;  // reported covariance = this x inverse information
  // Physical limits of the camera's motion since the last valid pose.
  double max_speed_m_s = 3.0;
  double max_rotation_rate_rad_s = 2.0 * 3.14159265358979;  // 360 deg/s
  // How far from its constant-velocity prediction the camera can be after dt: this times dt^2
  // (the prediction's velocity is the mean over the last interval, half an interval old): a
  // pose further is too fast, and other minima are looked for within it. 2 g, four times the
  // hand-held fr1_xyz and fr3_teddy peaks (the camera is at most 0.5 cm from its prediction at
  // 30 Hz, 2.4 cm at 10 Hz).
  double max_acceleration_m_s2 = 20.0;
};

// One bit per failed check; 0 = healthy.
enum HealthCheck : uint32_t {
  kFewResiduals = 1u << 0,
  kPhotometricMisfit = 1u << 1,  // a used term does not fit (agreement or inliers)
  kGeometricMisfit = 1u << 2,
  kCostAboveTypical = 1u << 3,  // the photometric scale jumped over its typical value
  kIllConditioned = 1u << 4,    // the used terms do not determine the pose
  kTooFast = 1u << 5,           // faster than the physical limits
  kWeakDirection = 1u << 6,     // a direction the depth leaves free is not determined either
  kAmbiguous = 1u << 7,         // another pose within the camera's reach fits about as well
  kDepthFrozen = 1u << 8,       // the sensor repeats its last depth frame (FrozenDepthCheck)
  kBeyondSearch = 1u << 9,      // the camera's reach is wider than the search for other minima
  kDepthUnits = 1u << 10,       // the depth's steps are not the sensor's (core/depth_units.hpp)
};

// FNV-1a over every 16th value: 19 200 of a VGA frame's pixels, about 20 us; a real sensor's
// noise changes thousands of them from one frame to the next.
uint64_t sampled_fingerprint(const uint16_t* values, int count);
uint64_t sampled_fingerprint(const uint8_t* values, int count);

// A depth sensor's noise makes any two of its frames differ in many pixels. A new depth frame
// (a new stamp) with the last one's content while the image has changed is a repeat; a stream
// that repeats itself frame after frame has stopped (a stuck driver buffer, a failed sensor)
// and whatever it shows, the geometry is not this frame's. One repeat alone is not enough: a
// recording paired by nearest stamp gives a depth frame to two colour frames (7 times in
// fr1_xyz's first 50), and one frame's lag is harmless. Sampled fingerprints; no copy.
class FrozenDepthCheck {
 public:
  static constexpr int kFrozenAfterRepeats = 2;
  // True when this frame's depth is the kFrozenAfterRepeats-th repeat in a row, or later.
  bool frozen(const uint16_t* depth, int64_t depth_stamp_ns, const uint8_t* gray, int pixels);

 private:
  uint64_t depth_ = 0, gray_ = 0;
  int64_t stamp_ns_ = 0;
  bool has_previous_ = false;
  int repeats_ = 0;
};

struct HealthContext {
  double typical_sigma = 0.0;  // photometric scale of healthy frames; 0 = not known yet
  // The motion since the last valid pose, and the time it took; dt 0 = no earlier pose.
  SE3 T_last_current;
  double dt_s = 0.0;
  // Where the camera was predicted, when the prediction holds up to its acceleration (a
  // velocity from two valid poses); the translation from it to the pose, m.
  bool predicted = false;
  double from_prediction_m = 0.0;
};

// The estimates' own noise, which a prediction from two of them carries: real frames lie up to
// 2.4 cm from their prediction at 30 Hz (fr1_xyz, fr3_teddy), of which the camera's own motion
// is 0.4 cm.
constexpr double kPoseNoiseM = 0.02;
// How far from its constant-velocity prediction the camera can be after dt_s, m.
double prediction_reach_m(double dt_s, const HealthLimits& limits);

// Two estimates of one pose that are the same minimum of the cost, not two: within a fifth of
// the false-valid limits (10 cm, 5 degrees).
constexpr double kSamePoseM = 0.02;
constexpr double kSamePoseRad = 1.0 * 3.14159265358979 / 180.0;
bool same_pose(const SE3& a, const SE3& b);

// The camera could have made this motion in dt_s (dt_s > 0); false for NaN.
bool within_motion_limits(const SE3& T_last_current, double dt_s, const HealthLimits& limits);

uint32_t failed_health_checks(const TrackResult& r, const HealthContext& context,
                              const HealthLimits& limits);
// The names of the failed checks, comma-separated, into buf (for STATUSTEXT and logs).
void describe_health(uint32_t failed, char* buf, int size);

}  // namespace rgbdtam

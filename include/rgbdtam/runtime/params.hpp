#pragma once
// Parameters, read once at start-up from a human-editable `key = value` file (key_value.hpp)
// into an immutable struct. The table in params.cpp is the one schema: every key's type, range,
// unit and meaning, used to validate, print and document. Defaults are the members' initialisers.

#include <cmath>
#include <cstdint>

#include "rgbdtam/core/camera.hpp"
#include "rgbdtam/core/pyramid.hpp"
#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/core/status.hpp"
#include "rgbdtam/core/tracker.hpp"
#include "rgbdtam/core/tracking_health.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/runtime/key_value.hpp"

namespace rgbdtam {

struct SensorModel {
  double depth_factor = 5000.0;              // raw depth units per metre
  DepthRange depth_range;                    // valid sensor depth, m
  double baseline_m = 0.075;                 // projector-camera baseline
  double depth_focal_px = 580.0;             // focal length of the IR camera
  double disparity_sigma_px = 0.4;           // effective disparity noise (see config/tum_fr1.conf)
  double disparity_quantum_px = 0.125;       // the disparity's sub-pixel step (PrimeSense: 1/8)
  int64_t max_rgb_depth_dt_ns = 20'000'000;  // pair colour and depth within 20 ms
  int64_t depth_time_offset_ns = 0;  // pair colour at t with the depth stamped nearest t + offset
  bool depth_at_its_instant = true;  // the depth's own instant: its stamp less the offset
  int64_t colour_readout_ns = 0;     // a rolling shutter's first to last row (0: all at once)
  int64_t depth_readout_ns = 0;      // the same for the depth image's rows
  // The paper's eq. for structured light: sigma_rho = sigma_d / (f b), constant in 1/m.
  double inverse_depth_sigma() const { return disparity_sigma_px / (depth_focal_px * baseline_m); }
  // The standard deviation of a uniform quantisation step, in inverse depth.
  double inverse_depth_quantum_sigma() const {
    return disparity_quantum_px / std::sqrt(12.0) / (depth_focal_px * baseline_m);
  }
};

// A depth camera of its own whose depth the device does not register to colour (RealSense and
// Orbbec over plain UVC): it is moved into the colour camera in software
// (core/depth_registration). Off where the device registers (Kinect v1, OpenNI2, TUM data).
struct DepthCameraParams {
  bool register_to_colour = false;
  PinholeIntrinsics intrinsics;  // its size 0x0 when it is the colour camera's
  RadTanDistortion distortion;
  SE3 T_c_d;  // colour camera from depth camera
};

// Loop closure, relocalisation and map reuse (paper sec. VI).
struct LoopParams {
  bool enabled = true;
  bool threaded = false;      // the loop module on its own thread (replay: synchronous)
  bool relocalise = true;     // look lost frames up in the places (else a restart waits for a loop)
  char vocabulary[128] = "";  // the vocabulary file, relative to the config file
  int places = 1024;          // light records remembered (the oldest goes when full)
  int features = 400;         // per keyframe
  int queue_keyframes = 4;    // tracker -> loop module slots
  // 3-D feature matches a rigid motion must explain to be a first guess of a place's pose (the
  // views' direct alignment decides whether it is the place).
  int min_inliers = 12;
  // A revisit optimises the map when it disagrees with it by more than this, and the
  // optimised map is sent to the tracker when some place moved by more than this.
  double min_correction_m = 0.02;
  double min_correction_rad = 1.0 * M_PI / 180.0;
  // The local window: each new keyframe's frame is also tracked, at full resolution, against
  // earlier keyframes that see much of it, and each measurement refines the map when it
  // disagrees with it by more than these; the refined map is sent when some keyframe moved
  // further. Small: a correction within max_reported_jump is blended into the poses sent. On:
  // over dithered copies of the development sequences it cuts the error of those that drift
  // most by a fifth to a half and costs the others up to 0.14 cm (docs/loop-closure.md, "The
  // local window"); a robot's worst drift matters more than its best case.
  bool window = true;
  // ... against up to this many of the earlier keyframes that see at least half of it, most
  // first; each is one more tracking on the keyframe builder's thread. Three: measured against
  // one, two and four over the same copies (the same page).
  int window_keyframes = 3;
  double min_window_correction_m = 0.002;
  double min_window_correction_rad = 0.1 * M_PI / 180.0;
  // A correction sent at once that moves the camera further than this is a jump a consumer
  // differencing poses would take for motion: the poses after it are withheld for that window
  // (reset_after_lost). Half the false-valid tolerance (10 cm, 5 degrees over 0.5 s), leaving
  // the other half to the tracker's own error.
  double max_reported_jump_m = 0.05;
  double max_reported_jump_rad = 2.5 * M_PI / 180.0;
  // A correction is not sent as a jump when the poses sent can move onto the corrected map at
  // most this fast within blend_within (0: every correction at once, with the reset counter).
  // At these rates any 0.5 s a consumer differences over holds at most one max_reported_jump's
  // worth, whatever the correction's size.
  double blend_rate_m_per_s = 0.1;
  double blend_rate_rad_per_s = 5.0 * M_PI / 180.0;
  // ArduPilot ignores vision data for 1 s after a reset, so a blend this long reaches it no later
  // than a jump would, and the poses go on meanwhile (10 cm and 5 degrees at the rates). Against
  // 0.5 s, over dithered copies with every limit a tenth: as accurate, and poses withheld on 2
  // of 16 fr3_teddy_200 copies instead of 11 (docs/loop-closure.md, "Corrections").
  int64_t blend_within_ns = 1'000'000'000;
  // A revisit that would move the map further than this fraction of the distance travelled
  // since the earlier place is more than odometry drifts (under 1 % on the development
  // sequences): the two places only look alike (panels, tiles) and neither relocalises or
  // closes a loop again.
  double max_drift_ratio = 0.1;
};

// What a run does with a map file it loads (--map-in, a board's map.file).
enum class MapMode {
  kSlam,      // extend it, and save it where asked
  kLocalise,  // track in it and leave it as it is: its places stay, the file is never written
};

struct Params {
  PinholeIntrinsics camera{517.3, 516.5, 318.6, 255.3, 640, 480};
  RadTanDistortion distortion;
  DepthCameraParams depth_camera;
  SensorModel sensor;
  TrackerOptions tracker;
  // The reported pose covariance is this times the inverse of the Gauss-Newton information,
  // which counts every residual as independent evidence; neighbouring pixels are not, and the
  // keyframe's depth errors are shared by all frames. Calibrated so that the frame-to-frame
  // NEES averages about 6 (docs/robust-tracking.md, "Reported covariance").
  double covariance_scale = 5000.0;
  int keyframe_pool_size = 32;
  int reuse_candidates = 2;  // nearest earlier keyframes tried before creating a new one
  HealthLimits health;       // what a pose must pass to be reported valid
  // Lost this long, tracking restarts at the last valid pose (reset_counter + 1). Not sooner
  // than the 0.5 s over which a consumer differences poses: the restart joins two stretches
  // whose relative pose is unknown, and within that window it would read as motion.
  int64_t reset_after_lost_ns = 500'000'000;
  // Multi-view mapping of each new keyframe (fr1_xyz all-frames ATE 0.84 cm with, 0.88 without).
  bool map_enabled = true;
  bool map_threaded = false;  // keyframe builder, mapper on threads of their own (replay: sync)
  int map_queue_frames = 4;   // tracker -> mapper queue slots
  int map_frames_per_keyframe = 10;  // frames triangulated per keyframe (code)
  // Spacing of triangulated frames relative to the median depth. All-frames ATE on fr1_xyz:
  // 0.91 cm at 0.005 and 0.01, 0.88 at 0.02, 0.87 at 0.03 (0.88 without mapping).
  double map_min_baseline_ratio = 0.03;
  int map_seeds = 10000;  // edge pixels mapped per keyframe
  MapMode map_mode = MapMode::kSlam;
  LoopParams loop;
};

// A velocity estimated across a longer gap (a loss, dropped frames) is not a velocity.
constexpr double kMaxVelocityGapS = 0.2;
// How far along a surface a keyframe's aliases are looked for: as far as the camera can move
// over the longest gap a velocity is measured across; a reach beyond it is ambiguous wherever
// a keyframe has aliases at all.
double alias_range_m(const Params& p);

// The sizes the sensor is opened at: depth at its camera's own (depth_camera.width/height) or
// colour's.
SensorImageSize sensor_image_size(const Params& p);
// The tracker's options with the sensor's noise model in them.
TrackerOptions tracking_options(const Params& p);
// The health limits with the covariance calibration in them.
HealthLimits health_limits(const Params& p);

// Parses `key = value` lines (# comments). `source` names the file in errors; a file path
// value (loop.vocabulary) is relative to source's folder.
Status parse_params(const char* text, const char* source, Params* out);
// Applies one `key=value` override, e.g. from the command line.
Status set_param(const char* assignment, const char* source, Params* out);
// Writes every key with its current value, unit and meaning.
void print_params(const Params& p, char* buf, int size, KeyListing listing = KeyListing::kFile);

}  // namespace rgbdtam

#include "rgbdtam/runtime/params.hpp"

#include <cstdio>
#include <cstring>

#include "rgbdtam/core/features.hpp"
#include "rgbdtam/runtime/key_value.hpp"

namespace rgbdtam {
namespace {

bool parse_residuals(const char* value, void* field) {
  return ResidualConfig::parse(value, static_cast<ResidualConfig*>(field));
}
void print_residuals(const void* field, char* out, size_t size) {
  static_cast<const ResidualConfig*>(field)->name(out, static_cast<int>(size));
}

bool parse_map_mode(const char* value, void* field) {
  MapMode* mode = static_cast<MapMode*>(field);
  if (std::strcmp(value, "slam") == 0) {
    *mode = MapMode::kSlam;
  } else if (std::strcmp(value, "localise") == 0) {
    *mode = MapMode::kLocalise;
  } else {
    return false;
  }
  return true;
}
void print_map_mode(const void* field, char* out, size_t size) {
  std::snprintf(out, size, "%s",
                *static_cast<const MapMode*>(field) == MapMode::kSlam ? "slam" : "localise");
}

#define RGBDTAM_FIELD(expr) [](void* p) -> void* { return &static_cast<Params*>(p)->expr; }

// The schema. Keys are stable: a removed key keeps its line as a comment.
const KeySpec kParamSpecs[] = {
    {"camera.width", ValueType::kInt, 8, 4096, "px", "image width, divisible by 8",
     RGBDTAM_FIELD(camera.width_px), true},
    {"camera.height", ValueType::kInt, 8, 4096, "px", "image height, divisible by 8",
     RGBDTAM_FIELD(camera.height_px), true},
    {"camera.fx", ValueType::kReal, 1, 1e5, "px", "focal length x", RGBDTAM_FIELD(camera.fx_px),
     true},
    {"camera.fy", ValueType::kReal, 1, 1e5, "px", "focal length y", RGBDTAM_FIELD(camera.fy_px),
     true},
    {"camera.cx", ValueType::kReal, -1e4, 1e4, "px", "principal point x",
     RGBDTAM_FIELD(camera.cx_px), true},
    {"camera.cy", ValueType::kReal, -1e4, 1e4, "px", "principal point y",
     RGBDTAM_FIELD(camera.cy_px), true},
    {"camera.k1", ValueType::kReal, -10, 10, "", "radial distortion k1",
     RGBDTAM_FIELD(distortion.k1), false},
    {"camera.k2", ValueType::kReal, -10, 10, "", "radial distortion k2",
     RGBDTAM_FIELD(distortion.k2), false},
    {"camera.p1", ValueType::kReal, -1, 1, "", "tangential distortion p1",
     RGBDTAM_FIELD(distortion.p1), false},
    {"camera.p2", ValueType::kReal, -1, 1, "", "tangential distortion p2",
     RGBDTAM_FIELD(distortion.p2), false},
    {"camera.k3", ValueType::kReal, -10, 10, "", "radial distortion k3",
     RGBDTAM_FIELD(distortion.k3), false},
    {"camera.readout_ms", ValueType::kMillisecondsAsNs, -100, 100, "ms",
     "a rolling shutter's time from the colour image's first row to its last, its middle row at "
     "its stamp (0: a global shutter; negative: the last row first)",
     RGBDTAM_FIELD(sensor.colour_readout_ns), false},
    {"depth_camera.fx", ValueType::kReal, 0, 1e5, "px", "depth camera focal length x",
     RGBDTAM_FIELD(depth_camera.intrinsics.fx_px), false},
    {"depth_camera.fy", ValueType::kReal, 0, 1e5, "px", "depth camera focal length y",
     RGBDTAM_FIELD(depth_camera.intrinsics.fy_px), false},
    {"depth_camera.cx", ValueType::kReal, -1e4, 1e4, "px", "depth camera principal point x",
     RGBDTAM_FIELD(depth_camera.intrinsics.cx_px), false},
    {"depth_camera.cy", ValueType::kReal, -1e4, 1e4, "px", "depth camera principal point y",
     RGBDTAM_FIELD(depth_camera.intrinsics.cy_px), false},
    {"depth_camera.width", ValueType::kInt, 0, 4096, "px",
     "depth image width when it differs from colour's (0: colour's; needs depth_camera.register)",
     RGBDTAM_FIELD(depth_camera.intrinsics.width_px), false},
    {"depth_camera.height", ValueType::kInt, 0, 4096, "px",
     "depth image height when it differs from colour's (0: colour's)",
     RGBDTAM_FIELD(depth_camera.intrinsics.height_px), false},
    {"depth_camera.k1", ValueType::kReal, -10, 10, "", "depth camera radial distortion k1",
     RGBDTAM_FIELD(depth_camera.distortion.k1), false},
    {"depth_camera.k2", ValueType::kReal, -10, 10, "", "depth camera radial distortion k2",
     RGBDTAM_FIELD(depth_camera.distortion.k2), false},
    {"depth_camera.p1", ValueType::kReal, -1, 1, "", "depth camera tangential distortion p1",
     RGBDTAM_FIELD(depth_camera.distortion.p1), false},
    {"depth_camera.p2", ValueType::kReal, -1, 1, "", "depth camera tangential distortion p2",
     RGBDTAM_FIELD(depth_camera.distortion.p2), false},
    {"depth_camera.k3", ValueType::kReal, -10, 10, "", "depth camera radial distortion k3",
     RGBDTAM_FIELD(depth_camera.distortion.k3), false},
    {"depth_camera.T_c_d", ValueType::kCustom, 0, 0, "",
     "colour camera from depth camera: qw qx qy qz (unit) tx ty tz (m)",
     RGBDTAM_FIELD(depth_camera.T_c_d), false, parse_pose_value, print_pose_value},
    {"depth_camera.register", ValueType::kBool, 0, 1, "",
     "move depth from its own camera (the depth_camera keys above) into the colour camera; off "
     "where the "
     "device registers it",
     RGBDTAM_FIELD(depth_camera.register_to_colour), false},
    {"depth.factor", ValueType::kReal, 1e-3, 1e6, "1/m", "raw depth units per metre",
     RGBDTAM_FIELD(sensor.depth_factor), true},
    {"depth.min", ValueType::kReal, 0.01, 100, "m", "nearest valid sensor depth",
     RGBDTAM_FIELD(sensor.depth_range.min_m), false},
    {"depth.max", ValueType::kReal, 0.1, 100, "m", "farthest valid sensor depth",
     RGBDTAM_FIELD(sensor.depth_range.max_m), false},
    {"depth.baseline", ValueType::kReal, 1e-3, 10, "m", "projector-camera baseline b",
     RGBDTAM_FIELD(sensor.baseline_m), false},
    {"depth.focal", ValueType::kReal, 1, 1e5, "px", "IR camera focal length f",
     RGBDTAM_FIELD(sensor.depth_focal_px), false},
    {"depth.disparity_sigma", ValueType::kReal, 1e-4, 10, "px", "disparity noise sigma_d",
     RGBDTAM_FIELD(sensor.disparity_sigma_px), false},
    {"depth.disparity_quantum", ValueType::kReal, 1e-4, 10, "px",
     "the disparity's sub-pixel step (its quantisation floors the geometric scale)",
     RGBDTAM_FIELD(sensor.disparity_quantum_px), false},
    {"depth.max_rgb_dt_ms", ValueType::kMillisecondsAsNs, 0, 1000, "ms",
     "largest colour-depth time difference", RGBDTAM_FIELD(sensor.max_rgb_depth_dt_ns), false},
    {"depth.time_offset_ms", ValueType::kMillisecondsAsNs, -100, 100, "ms",
     "pair colour at t with the depth stamped nearest t + offset",
     RGBDTAM_FIELD(sensor.depth_time_offset_ns), false},
    {"depth.at_its_instant", ValueType::kBool, 0, 1, "",
     "track each depth image from where the camera was when it was taken (its stamp less the "
     "offset; the motion model's velocity)",
     RGBDTAM_FIELD(sensor.depth_at_its_instant), false},
    {"depth.readout_ms", ValueType::kMillisecondsAsNs, -100, 100, "ms",
     "the same for the depth image's rows, its middle row at the depth's instant",
     RGBDTAM_FIELD(sensor.depth_readout_ns), false},
    {"tracker.residuals", ValueType::kCustom, 0, 0, "",
     "PS, PD, GIDS, GIDD, GIDD*, PS+GIDD, PS+GDD, ...", RGBDTAM_FIELD(tracker.residuals), false,
     parse_residuals, print_residuals},
    {"tracker.photometric_points", ValueType::kInt, 10, 1e6, "",
     "photometric points at the finest level (x1/3 per level)",
     RGBDTAM_FIELD(tracker.photometric_points_finest), false},
    {"tracker.gradient_top_fraction", ValueType::kFloat, 0.01, 1, "",
     "fraction of strongest gradients eligible as points",
     RGBDTAM_FIELD(tracker.gradient_top_fraction), false},
    {"tracker.canny_low", ValueType::kFloat, 1, 2000, "grey/px",
     "Canny low threshold (Sobel-3 magnitude)", RGBDTAM_FIELD(tracker.canny_low), false},
    {"tracker.canny_high", ValueType::kFloat, 1, 2000, "grey/px", "Canny high threshold",
     RGBDTAM_FIELD(tracker.canny_high), false},
    {"tracker.iterations_l0", ValueType::kInt, 0, 100, "", "Gauss-Newton iterations at 640x480",
     RGBDTAM_FIELD(tracker.max_iterations[0]), false},
    {"tracker.iterations_l1", ValueType::kInt, 0, 100, "", "Gauss-Newton iterations at 320x240",
     RGBDTAM_FIELD(tracker.max_iterations[1]), false},
    {"tracker.iterations_l2", ValueType::kInt, 0, 100, "", "Gauss-Newton iterations at 160x120",
     RGBDTAM_FIELD(tracker.max_iterations[2]), false},
    {"tracker.iterations_l3", ValueType::kInt, 0, 100, "", "Gauss-Newton iterations at 80x60",
     RGBDTAM_FIELD(tracker.max_iterations[3]), false},
    {"tracker.min_relative_decrease", ValueType::kReal, 0, 1, "",
     "stop a level below this relative cost decrease", RGBDTAM_FIELD(tracker.min_relative_decrease),
     false},
    {"tracker.robust_c", ValueType::kReal, 0.1, 100, "sigma", "Geman-McClure scale",
     RGBDTAM_FIELD(tracker.robust_c), false},
    {"tracker.geometric_weight", ValueType::kReal, 0, 1000, "",
     "lambda on the normalised geometric error", RGBDTAM_FIELD(tracker.geometric_weight), false},
    {"tracker.keyframe_overlap", ValueType::kReal, 0, 1, "",
     "new keyframe below this overlap (its points visible and within 3 typical sigmas)",
     RGBDTAM_FIELD(tracker.keyframe_overlap), false},
    {"tracker.keyframe_parallax", ValueType::kReal, 0.001, 10, "",
     "new keyframe when the camera moved this fraction of the scene depth",
     RGBDTAM_FIELD(tracker.keyframe_parallax), false},
    {"tracker.covariance_scale", ValueType::kReal, 1, 1e9, "",
     "reported pose covariance = this x inverse information (calibrated by NEES)",
     RGBDTAM_FIELD(covariance_scale), false},
    {"tracker.gain_brightness", ValueType::kBool, 0, 1, "", "estimate gain and brightness",
     RGBDTAM_FIELD(tracker.gain_brightness), false},
    {"tracker.motion_model", ValueType::kBool, 0, 1, "", "constant-velocity initial guess",
     RGBDTAM_FIELD(tracker.motion_model), false},
    {"map.keyframe_pool", ValueType::kInt, 3, 4096, "",
     "keyframes kept; when full the oldest non-reference one is recycled",
     RGBDTAM_FIELD(keyframe_pool_size), false},
    {"map.reuse_candidates", ValueType::kInt, 0, 16, "",
     "nearest earlier keyframes tried before creating a new one (0: no map reuse)",
     RGBDTAM_FIELD(reuse_candidates), false},
    {"map.enabled", ValueType::kBool, 0, 1, "", "multi-view mapping of each new keyframe",
     RGBDTAM_FIELD(map_enabled), false},
    {"map.threaded", ValueType::kBool, 0, 1, "",
     "build keyframes and map on threads of their own (else synchronously, deterministic)",
     RGBDTAM_FIELD(map_threaded), false},
    {"map.queue_frames", ValueType::kInt, 1, 64, "",
     "tracker-to-mapper queue slots; a full queue drops the frame", RGBDTAM_FIELD(map_queue_frames),
     false},
    {"map.frames_per_keyframe", ValueType::kInt, 1, 100, "", "frames triangulated per keyframe",
     RGBDTAM_FIELD(map_frames_per_keyframe), false},
    {"map.min_baseline_ratio", ValueType::kReal, 0, 1, "",
     "spacing of triangulated frames, relative to the median depth",
     RGBDTAM_FIELD(map_min_baseline_ratio), false},
    {"map.seeds", ValueType::kInt, 100, 100000, "", "edge pixels mapped per keyframe",
     RGBDTAM_FIELD(map_seeds), false},
    {"map.mode", ValueType::kCustom, 0, 0, "",
     "slam: a loaded map is extended; localise: tracked in, never changed or written",
     RGBDTAM_FIELD(map_mode), false, parse_map_mode, print_map_mode},
    {"loop.enabled", ValueType::kBool, 0, 1, "",
     "loop closure, relocalisation and map reuse (needs loop.vocabulary)",
     RGBDTAM_FIELD(loop.enabled), false},
    {"loop.threaded", ValueType::kBool, 0, 1, "",
     "run the loop module on its own thread (else synchronously, deterministic)",
     RGBDTAM_FIELD(loop.threaded), false},
    {"loop.relocalise", ValueType::kBool, 0, 1, "",
     "look lost frames up in the map (else a restart joins the map at the next loop)",
     RGBDTAM_FIELD(loop.relocalise), false},
    {"loop.vocabulary", ValueType::kText, 0, 0, "",
     "bag-of-words vocabulary file (rgbdtam vocabulary train), relative to this file",
     RGBDTAM_FIELD(loop.vocabulary), false},
    {"loop.places", ValueType::kInt, 8, 100000, "",
     "keyframes remembered as places; when full the oldest is forgotten",
     RGBDTAM_FIELD(loop.places), false},
    {"loop.features", ValueType::kInt, 50, 4000, "", "features per keyframe",
     RGBDTAM_FIELD(loop.features), false},
    {"loop.queue_keyframes", ValueType::kInt, 1, 64, "",
     "tracker-to-loop queue slots; a full queue leaves the keyframe out of the map",
     RGBDTAM_FIELD(loop.queue_keyframes), false},
    // loop.min_age: gone; candidates are excluded by the graph's neighbourhood, not by age.
    {"loop.min_inliers", ValueType::kInt, 6, 4000, "",
     "3-D feature matches one rigid motion must explain to give a first guess of a place's pose",
     RGBDTAM_FIELD(loop.min_inliers), false},
    // loop.consistent_queries: gone; each revisit is verified by aligning the views both ways.
    {"loop.min_correction", ValueType::kReal, 0, 10, "m",
     "a revisit optimises the map when it disagrees with it beyond this, and a correction is "
     "sent when the map moved further",
     RGBDTAM_FIELD(loop.min_correction_m), false},
    {"loop.min_correction_angle", ValueType::kDegreesAsRadians, 0, 180, "deg",
     "... or beyond this angle", RGBDTAM_FIELD(loop.min_correction_rad), false},
    {"loop.window", ValueType::kBool, 0, 1, "",
     "track each new keyframe also against earlier keyframes that see much of it, and refine the "
     "map with those measurements",
     RGBDTAM_FIELD(loop.window), false},
    {"loop.window_keyframes", ValueType::kInt, 1, kMaxWindowEdges, "",
     "... against this many of the earlier keyframes that see at least half of it, most first",
     RGBDTAM_FIELD(loop.window_keyframes), false},
    {"loop.min_window_correction", ValueType::kReal, 0, 10, "m",
     "a window measurement refines the map when it disagrees with it beyond this, and the refined "
     "map is sent when some keyframe moved further",
     RGBDTAM_FIELD(loop.min_window_correction_m), false},
    {"loop.min_window_correction_angle", ValueType::kDegreesAsRadians, 0, 180, "deg",
     "... or beyond this angle", RGBDTAM_FIELD(loop.min_window_correction_rad), false},
    {"loop.max_reported_jump", ValueType::kReal, 0, 10, "m",
     "a correction sent at once (not blended) moving the camera further withholds poses for "
     "health.reset_after_lost_ms",
     RGBDTAM_FIELD(loop.max_reported_jump_m), false},
    {"loop.max_reported_jump_angle", ValueType::kDegreesAsRadians, 0, 180, "deg",
     "... or turning it further", RGBDTAM_FIELD(loop.max_reported_jump_rad), false},
    {"loop.blend_rate", ValueType::kReal, 0, 10, "m/s",
     "a correction reaches the poses sent at most this fast, with no jump and no reset, when that "
     "takes at most loop.blend_within_ms; else at once, with the reset counter (0: always at once)",
     RGBDTAM_FIELD(loop.blend_rate_m_per_s), false},
    {"loop.blend_rate_angle", ValueType::kDegreesAsRadians, 0, 1000, "deg/s",
     "... and turns them at most this fast", RGBDTAM_FIELD(loop.blend_rate_rad_per_s), false},
    {"loop.blend_within_ms", ValueType::kMillisecondsAsNs, 0, 1e5, "ms",
     "the longest a correction may take to reach the poses sent (ArduPilot ignores vision for 1 s "
     "after a reset)",
     RGBDTAM_FIELD(loop.blend_within_ns), false},
    {"loop.max_drift", ValueType::kReal, 0.001, 10, "",
     "a revisit moving the map further than this fraction of the distance travelled since the "
     "earlier place is a look-alike, not a loop: neither place is used again",
     RGBDTAM_FIELD(loop.max_drift_ratio), false},
    // tracker.lost_sigma_ratio: now health.max_sigma_ratio.
    // tracker.lost_frames_before_reset: now health.reset_after_lost_ms.
    {"health.min_residuals", ValueType::kInt, 6, 1e6, "",
     "valid residuals a pose needs at the finest level", RGBDTAM_FIELD(health.min_residuals),
     false},
    {"health.max_agreement", ValueType::kReal, 0.01, 10, "",
     "lost above this residual spread over the keyframe's spread (unrelated image: 1.41)",
     RGBDTAM_FIELD(health.max_agreement), false},
    {"health.min_inliers", ValueType::kReal, 0, 1, "",
     "lost below this fraction of a term's residuals within 3 reference sigmas",
     RGBDTAM_FIELD(health.min_inliers), false},
    {"health.max_sigma_ratio", ValueType::kReal, 1, 1000, "",
     "lost when the photometric sigma exceeds this factor times its typical value",
     RGBDTAM_FIELD(health.max_sigma_ratio), false},
    {"health.max_translation_std", ValueType::kReal, 1e-6, 100, "m",
     "lost when the pose's 1-sigma exceeds this along some direction",
     RGBDTAM_FIELD(health.max_translation_std_m), false},
    {"health.max_rotation_std", ValueType::kDegreesAsRadians, 1e-4, 180, "deg",
     "lost when the rotation's 1-sigma exceeds this about some axis",
     RGBDTAM_FIELD(health.max_rotation_std_rad), false},
    {"health.max_weak_direction_std", ValueType::kReal, 1e-6, 100, "m",
     "lost when a direction the depth leaves free has a reported 1-sigma above this",
     RGBDTAM_FIELD(health.max_weak_direction_std_m), false},
    {"health.max_speed", ValueType::kReal, 0.01, 1000, "m/s",
     "lost when the camera moved faster than this since the last valid pose",
     RGBDTAM_FIELD(health.max_speed_m_s), false},
    {"health.max_rotation_rate", ValueType::kDegreesAsRadians, 1, 100000, "deg/s",
     "lost when the camera turned faster than this since the last valid pose",
     RGBDTAM_FIELD(health.max_rotation_rate_rad_s), false},
    {"health.max_acceleration", ValueType::kReal, 0.1, 10000, "m/s^2",
     "how far the camera can be from its constant-velocity prediction: lost beyond it, and "
     "ambiguous when another pose within it fits about as well",
     RGBDTAM_FIELD(health.max_acceleration_m_s2), false},
    {"health.reset_after_lost_ms", ValueType::kMillisecondsAsNs, 0, 1e6, "ms",
     "lost this long, tracking restarts at the last valid pose", RGBDTAM_FIELD(reset_after_lost_ns),
     false},
};
#undef RGBDTAM_FIELD

constexpr KeyTable kParamTable{kParamSpecs, sizeof(kParamSpecs) / sizeof(kParamSpecs[0])};

Status check_consistency(const char* source, const Params& p) {
  if (p.camera.width_px % 8 != 0 || p.camera.height_px % 8 != 0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: keys 'camera.width'/'camera.height' must be divisible by 8 "
                         "for the 4-level pyramid (got %dx%d)",
                         source, p.camera.width_px, p.camera.height_px);
  }
  // The smallest size every component takes: features keep a border on each side, and the
  // pyramid halves three times.
  constexpr int kMinSidePx = (2 * kFeatureBorderPx / 8 + 1) * 8;
  if (p.camera.width_px < kMinSidePx || p.camera.height_px < kMinSidePx) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: keys 'camera.width'/'camera.height' must be at least %d px (place "
                         "recognition's features keep %d px from each border; got %dx%d)",
                         source, kMinSidePx, kFeatureBorderPx, p.camera.width_px,
                         p.camera.height_px);
  }
  if (p.sensor.depth_range.min_m >= p.sensor.depth_range.max_m) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: key 'depth.min' (%g) must be below 'depth.max' (%g)", source,
                         p.sensor.depth_range.min_m, p.sensor.depth_range.max_m);
  }
  const PinholeIntrinsics& depth_size = p.depth_camera.intrinsics;
  if ((depth_size.width_px > 0) != (depth_size.height_px > 0) ||
      (depth_size.width_px > 0 && !p.depth_camera.register_to_colour)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: keys 'depth_camera.width'/'depth_camera.height' (%dx%d) give a depth "
                         "image of its own size: both or neither, and only with "
                         "'depth_camera.register = true' (registered depth is colour's size)",
                         source, depth_size.width_px, depth_size.height_px);
  }
  if (depth_size.width_px > 0 && (depth_size.width_px < 8 || depth_size.height_px < 8)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: keys 'depth_camera.width'/'depth_camera.height' must be at least 8 "
                         "px (got %dx%d)",
                         source, depth_size.width_px, depth_size.height_px);
  }
  if (p.depth_camera.register_to_colour) {
    const PinholeIntrinsics& k = p.depth_camera.intrinsics;
    if (k.fx_px <= 0 || k.fy_px <= 0) {
      return Status::error(StatusCode::kInvalidArgument,
                           "%s: key 'depth_camera.register' needs the depth camera's "
                           "'depth_camera.fx'/'depth_camera.fy' (and cx, cy, its distortion and "
                           "depth_camera.T_c_d)",
                           source);
    }
    // One device's two cameras sit centimetres apart.
    constexpr double kMaxBaselineM = 0.3;
    if (p.depth_camera.T_c_d.translation().norm() > kMaxBaselineM) {
      return Status::error(StatusCode::kInvalidArgument,
                           "%s: key 'depth_camera.T_c_d' puts the depth camera %.2f m from the "
                           "colour camera (at most %.1f: translation in metres, not mm?)",
                           source, p.depth_camera.T_c_d.translation().norm(), kMaxBaselineM);
    }
  }
  // The reference, three keyframes being mapped, one per queue slot, and a free one.
  const int pool_needed = p.map_queue_frames + 5;
  if (p.map_enabled && p.keyframe_pool_size < pool_needed) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: key 'map.keyframe_pool' (%d) must be at least map.queue_frames + 5 "
                         "(%d) when mapping is enabled",
                         source, p.keyframe_pool_size, pool_needed);
  }
  int iterations = 0;
  for (const int n : p.tracker.max_iterations) iterations += n;
  if (iterations == 0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: keys 'tracker.iterations_l0'..'l3' are all 0: the tracker would "
                         "never move from its prediction (one level at 0 is fine)",
                         source);
  }
  if (p.tracker.canny_low > p.tracker.canny_high) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: key 'tracker.canny_low' must not exceed 'tracker.canny_high'",
                         source);
  }
  return Status::ok();
}
}  // namespace

namespace {
// A file named in a parameter file is found beside it: a relative path gets the folder of
// `source` (when it has one) in front.
Status resolve_beside(const char* source, const char* key, char* path, size_t size) {
  const char* slash = std::strrchr(source, '/');
  if (path[0] == '\0' || path[0] == '/' || slash == nullptr) return Status::ok();
  char joined[kTextBytes];
  const int n = std::snprintf(joined, sizeof(joined), "%.*s/%s", static_cast<int>(slash - source),
                              source, path);
  if (n < 0 || static_cast<size_t>(n) >= sizeof(joined) || static_cast<size_t>(n) >= size) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: key '%s': the path joined to the file's folder is too long", source,
                         key);
  }
  std::memcpy(path, joined, static_cast<size_t>(n) + 1);
  return Status::ok();
}
}  // namespace

TrackerOptions tracking_options(const Params& p) {
  TrackerOptions o = p.tracker;
  o.inverse_depth_sigma = p.sensor.inverse_depth_sigma();
  o.inverse_depth_sigma_floor = p.sensor.inverse_depth_quantum_sigma();
  return o;
}

SensorImageSize sensor_image_size(const Params& p) {
  const PinholeIntrinsics& depth = p.depth_camera.intrinsics;
  SensorImageSize size = same_size(p.camera.width_px, p.camera.height_px);
  if (p.depth_camera.register_to_colour && depth.width_px > 0) {
    size.depth_width_px = depth.width_px;
    size.depth_height_px = depth.height_px;
  }
  return size;
}

double alias_range_m(const Params& p) { return p.health.max_speed_m_s * kMaxVelocityGapS; }

HealthLimits health_limits(const Params& p) {
  HealthLimits h = p.health;
  h.covariance_scale = p.covariance_scale;
  return h;
}

Status parse_params(const char* text, const char* source, Params* out) {
  Params p = *out;
  p.loop.vocabulary[0] = '\0';
  RGBDTAM_RETURN_IF_ERROR(parse_key_values(text, source, kParamTable, &p));
  if (p.loop.vocabulary[0] == '\0') {
    std::memcpy(p.loop.vocabulary, out->loop.vocabulary, sizeof(p.loop.vocabulary));
  } else {
    RGBDTAM_RETURN_IF_ERROR(
        resolve_beside(source, "loop.vocabulary", p.loop.vocabulary, sizeof(p.loop.vocabulary)));
  }
  RGBDTAM_RETURN_IF_ERROR(check_consistency(source, p));
  *out = p;
  return Status::ok();
}

Status set_param(const char* assignment, const char* source, Params* out) {
  Params p = *out;
  RGBDTAM_RETURN_IF_ERROR(apply_key_value(assignment, source, kParamTable, &p));
  RGBDTAM_RETURN_IF_ERROR(check_consistency(source, p));
  *out = p;
  return Status::ok();
}

void print_params(const Params& in, char* buf, int size, KeyListing listing) {
  Params p = in;
  print_key_values(kParamTable, &p, buf, size, listing);
}

}  // namespace rgbdtam

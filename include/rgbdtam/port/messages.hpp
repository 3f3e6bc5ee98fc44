#pragma once
// Typed, fixed-size messages between modules, all of them here. Timestamps are integer nanoseconds;
// poses are T_w_c (world from camera), world = the first keyframe's camera frame.

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rgbdtam/core/attitude.hpp"
#include "rgbdtam/core/fixed_vector.hpp"
#include "rgbdtam/core/image.hpp"
#include "rgbdtam/core/obstacle_sectors.hpp"
#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/core/view_alignment.hpp"
#include "rgbdtam/port/status_text.hpp"

namespace rgbdtam {

// Sensor source -> pipeline. Written by a sensor source (replay or live), read by the
// tracker on the same thread. The pixel buffers belong to the source and stay valid until
// its next frame.
struct SensorFrame {
  uint32_t sequence = 0;           // index in the source, counting skipped frames
  int64_t timestamp_ns = 0;        // colour exposure
  int64_t depth_timestamp_ns = 0;  // 0 when there is no depth for this frame
  const uint8_t* gray = nullptr;   // width*height, 8-bit grey, distorted (raw)
  // depth_width*depth_height raw depth, or null: registered to colour (and of its size) unless
  // the sensor's depth camera has its own (depth_camera.register), until DepthInColour moves it.
  const uint16_t* depth = nullptr;
  int width_px = 0;
  int height_px = 0;
  int depth_width_px = 0;
  int depth_height_px = 0;
};

// The sizes a sensor delivers its two images at.
struct SensorImageSize {
  int width_px = 0, height_px = 0;              // colour
  int depth_width_px = 0, depth_height_px = 0;  // depth
  size_t pixels() const { return static_cast<size_t>(width_px) * static_cast<size_t>(height_px); }
  size_t depth_pixels() const {
    return static_cast<size_t>(depth_width_px) * static_cast<size_t>(depth_height_px);
  }
};

// Both images of one size (a sensor that registers depth to colour).
inline SensorImageSize same_size(int width_px, int height_px) {
  return {width_px, height_px, width_px, height_px};
}

// Estimator health bits in PoseEstimate::flags.
enum PoseFlags : uint32_t {
  kPoseValid = 1u << 0,       // T_w_c holds an estimate for this frame
  kNewKeyframe = 1u << 1,     // this frame became the tracking reference
  kNoDepth = 1u << 2,         // tracked with the photometric term only
  kLost = 1u << 3,            // tracking failed on this frame
  kReset = 1u << 4,           // estimate restarted (jump); see reset_counter
  kNotInitialised = 1u << 5,  // no keyframe yet (waiting for a frame with depth)
  kKeyframeReused = 1u << 6,  // an earlier keyframe became the reference again (map reuse)
  kRelocalised = 1u << 7,     // lost, then found again in the map (with kReset)
  kLoopCorrected = 1u << 8,   // a loop closure moved the map (with kReset unless blended in)
  kSettling = 1u << 9,        // tracked, but withheld: too soon after a correction to compare poses
  kLocalising = 1u << 10,     // a map was loaded and this frame is not found in it yet: no pose
  kBlending = 1u << 11,       // the pose moves onto a corrected map, at most loop.blend_rate
};

// Pipeline -> trajectory writer, link. One per input frame.
struct PoseEstimate {
  uint32_t sequence = 0;
  int64_t timestamp_ns = 0;  // colour timestamp of the frame
  SE3 T_w_c;
  // Tracking's own pose, on the map as corrected now: T_w_c differs from it while a correction is
  // being blended into the poses sent (kBlending).
  SE3 T_w_c_map;
  uint32_t flags = 0;
  uint32_t keyframe_id = 0;
  uint32_t reset_counter = 0;
  float overlap = 0.f;            // keyframe points seen in this frame as they were, [0,1]
  float photometric_sigma = 0.f;  // intensity units [0,1]
  int32_t residuals_used = 0;
  int32_t iterations = 0;
  uint32_t failed_checks = 0;  // HealthCheck bits of a frame reported lost
  // Finest-level J^T W J of the tracker's keyframe-side perturbation, (v, omega); zero when
  // the pose is not valid.
  Eigen::Matrix<double, 6, 6> information;
};

// The covariance sent with a pose: the inverse of its information (NaN where it has none), over
// (translation, rotation) in the camera frame.
Eigen::Matrix<double, 6, 6> pose_covariance(const PoseEstimate& pose);

// How a keyframe's pose was measured against the keyframe it names as its reference.
enum class EdgeKind : uint8_t {
  kOdometry,        // tracked against it
  kRestart,         // none: tracking restarted, the two poses are not related
  kRelocalisation,  // a lost frame found again at the reference's place
  kCovisible,       // graph edges the loop module adds: a neighbour's view aligned ...
  kRevisit,         // ... a place revisited, its view aligned
  kReuse,           // the tracker took up an earlier keyframe again (map reuse)
};

// The local window's measurements of a new keyframe: against at most this many earlier keyframes
// (loop.window_keyframes).
constexpr int kMaxWindowEdges = 4;

// One of them: the keyframe in the earlier one, with its information (graph convention).
struct WindowEdge {
  uint32_t window_id = 0;
  SE3 T_window_keyframe;
  Matrix6d information = Matrix6d::Zero();
};

// Tracker -> loop module: a new keyframe (kind kKeyframe), or the tracker taking up an earlier
// keyframe (kReuse: keyframe_id is the earlier one, reference_id the one left; no images).
// The slot owns its images.
struct LoopKeyframe {
  enum class Kind : uint8_t { kKeyframe, kReuse };
  Kind kind = Kind::kKeyframe;
  uint32_t keyframe_id = 0;
  uint32_t reference_id = 0;                      // the keyframe it was measured against
  EdgeKind reference_edge = EdgeKind::kOdometry;  // ... and how
  uint32_t corrections_adopted = 0;  // LoopCorrections the tracker had applied when it was made
  int64_t timestamp_ns = 0;
  SE3 T_w_k;
  // The measurement: the keyframe in its reference, and its information for a right
  // perturbation T_reference_keyframe exp(xi), xi = (v, omega); zero for a restart.
  SE3 T_reference_keyframe;
  Matrix6d information = Matrix6d::Zero();
  // The local window's further measurements: the keyframe's frame tracked at full resolution,
  // as against its reference, against earlier keyframes that see much of it, most first.
  WindowEdge window[kMaxWindowEdges];
  int window_edges = 0;
  ImageF gray;           // level 0, undistorted, [0,1]
  ImageF inverse_depth;  // level 0 sensor inverse depth, 1/m
  View view;             // the pyramid's view level, remembered with the place
  bool repeats = false;  // the keyframe's image matches itself shifted (KeyframeAliases)
};

struct KeyframePose {
  uint32_t keyframe_id = 0;
  SE3 T_w_k;
};

// Loop module -> tracker, after a loop closure: every remembered keyframe's corrected pose,
// sorted by id. The tracker adopts it between frames.
struct LoopCorrection {
  FixedVector<KeyframePose> poses;
};

// A dense keyframe of the KeyframePool: its slot, and the slot's generation when named (a
// recycled slot has another, so a stale handle is detected).
struct KeyframeHandle {
  int32_t slot = -1;
  uint32_t generation = 0;
};

// Which frame the camera's world is in. A restart or a relocalisation moves it by a motion
// nothing measured (a new epoch); a loop correction by a known one, T_now_epoch's step.
struct MapFrame {
  uint32_t epoch = 0;
  uint32_t corrections = 0;  // in this epoch
  SE3 T_now_epoch;           // the world now from the world the epoch began in
  // How poses of an earlier frame map into this one: false across epochs.
  bool moved_from(const MapFrame& earlier, SE3* T_now_earlier) const {
    if (earlier.epoch != epoch) return false;
    *T_now_earlier = T_now_epoch * earlier.T_now_epoch.inverse();
    return true;
  }
  bool same_as(const MapFrame& other) const {
    return other.epoch == epoch && other.corrections == corrections;
  }
};

// Tracker -> mapper, one per tracked frame. The slot owns its images.
struct MapperFrame {
  uint32_t sequence = 0;
  MapFrame map_frame;  // the frame T_w_c is in
  int64_t timestamp_ns = 0;
  SE3 T_w_c;
  KeyframeHandle new_keyframe;  // set when this frame became a keyframe (pinned for the mapper)
  ImageF gray;                  // level 0, undistorted, [0,1]
  ImageF inverse_depth;         // level 0 sensor inverse depth; filled for keyframes only
  ImageU8 edges;                // level 0 Canny edges; filled for keyframes only
};

// Tracker -> keyframe builder: build the keyframe of the frame in hand.
struct KeyframeOrder {
  uint32_t id = 0;
  int64_t timestamp_ns = 0;
  SE3 T_w_k;
  SE3 T_c_d;                                     // the frame's depth camera (FramePyramid::T_c_d)
  Vector6d row_motion = Vector6d::Zero();        // its rolling shutter (FramePyramid)
  Vector6d depth_row_motion = Vector6d::Zero();  // ... and its depth image's
  bool with_local_maps = false;  // the local maps fill the pixels the sensor did not measure
};

// Autopilot (through the link) -> tracker's attitude prior: AttitudeSample, declared in
// core/attitude.hpp because core's AttitudeHistory stores it.

// Tracker (and firmware events) -> link task.
struct LinkMessage {
  enum class Kind : uint8_t { kPose, kStatus, kObstacles };
  Kind kind = Kind::kPose;
  PoseEstimate pose;
  int64_t arrival_ns = 0;  // when the pose's frame arrived, on the link's clock
  bool levelled = false;   // q_l_w holds the level frame (gravity from the autopilot)
  Eigen::Quaterniond q_l_w = Eigen::Quaterniond::Identity();
  ObstacleSectors obstacles;
  int64_t obstacles_timestamp_ns = 0;  // their depth frame's, in the sensor's clock
  uint8_t severity = 0;
  char text[kMaxStatusTextChars + 1] = {};  // sent in 50-character STATUSTEXT chunks
};

}  // namespace rgbdtam

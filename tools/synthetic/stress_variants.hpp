#pragma once
// Stress variants of TUM RGB-D sequences, each written as a new TUM folder that keeps the
// original's ground truth (tools/robustness.sh, the robustness tests). Host side: allocates.

#include <string>

#include "synthetic_scene.hpp"

namespace rgbdtam::testing {

// A depth camera beside the colour camera, as a RealSense or Orbbec has one: baseline_m to its
// side, focal_scale times its focal length, its own principal point and distortion, under a
// degree of rotation, and an image of its own size (0: the colour camera's).
struct DepthCameraShape {
  double focal_scale = 1.08;
  double baseline_m = 0.025;
  int width_px = 0, height_px = 0;
};

// Every n-th colour frame (the same motion, n times faster); images are linked, not copied.
bool decimate_sequence(const std::string& in, const std::string& out, int n);
// A sensor outage: `count` colour frames from the `first` cut out.
bool cut_frames(const std::string& in, const std::string& out, int first, int count);
// A kidnapped frame: colour frame `frame` (and the depth paired with it) shows what frame
// `from` showed, under its own timestamps, as if the sensor had jumped there for one frame.
bool kidnap_frame(const std::string& in, const std::string& out, int frame, int from);
// Depth frames removed: every n-th (every > 1), or `burst` of every `period`.
bool drop_depth_frames(const std::string& in, const std::string& out, int every, int burst,
                       int period);
// Motion blur along the ground-truth motion: each pixel is averaged over the exposure, sampling
// the frame where the camera at each instant would have seen it (the pixel's own depth, or
// the frame's median where there is none; lens distortion is ignored by the warp). Frames the
// ground truth does not cover stay sharp. config gives the camera and the depth pairing.
bool blur_sequence(const std::string& in, const std::string& out, const std::string& config,
                   double exposure_ms);
// Pure noise in place of the depth images, the colour images or both (kind: depth, colour,
// both), from a fixed seed; stamps and ground truth as recorded. Depth is uniform over the
// sensor's range. Or depth as a failed sensor gives it, one raw value in every pixel of every
// frame: 1 m (depth-1m), 0 (depth-zero) or 65535 (depth-saturated). config gives the image
// size, the depth scale and the range.
bool noise_sequence(const std::string& in, const std::string& out, const std::string& config,
                    const std::string& kind, unsigned seed);
// The sequence played forwards and then backwards: the reversed frames get new, increasing
// stamps mirrored about the last frame's, and their ground truth is the original's. The depth
// stamps are mirrored about the colour-depth pairing offset of config, so that each reversed
// colour frame pairs with the depth it paired with going forwards.
bool there_and_back(const std::string& in, const std::string& out, const std::string& config);
// The room pan_sequence renders: the camera panning at up to peak_deg_s, within a
// structured-light sensor's range.
SyntheticScene pan_scene(double peak_deg_s);
// A synthetic room seen by a camera panning at up to peak_deg_s, with exact ground truth and
// its config as out/camera.conf; each depth image taken depth_late_ms after its colour image (as
// a Kinect streams the two unsynchronised) and stamped so; the colour image's rows read out
// over readout_ms (a rolling shutter; 0: all at once).
bool pan_sequence(const std::string& out, double peak_deg_s, int frames, double fps,
                  double depth_late_ms = 0.0, double readout_ms = 0.0);
// A static camera, mounted looking forward (as the boards' link.T_b_c), before a textured wall
// whose normal lies distance_m from it at yaw_deg clockwise from forward, at 30 Hz
// (OBSTACLE_DISTANCE's geometry check: tools/mavlink-check).
bool wall_sequence(const std::string& out, double distance_m, double yaw_deg, int frames);
// The second sequence after the first, gap_s after its last frame (a sensor outage between
// two passes; variants of one sequence share its ground truth's frame).
bool concatenate(const std::string& first, const std::string& second, const std::string& out,
                 double gap_s);
// A long wander over a sequence, for soaks: `frames` frames in segments of a tenth to a half of
// the sequence played forwards or backwards at 1x or 2x, every fifth beginning after an outage
// of 0.5-2 s, elsewhere in the sequence. Each frame keeps its image pair and its true pose under
// new 30 Hz stamps (depth at config's pairing offset), so places repeat at other times.
bool wander_sequence(const std::string& in, const std::string& out, const std::string& config,
                     int frames, unsigned seed);
// The depth of a sequence registered to colour moved out into a depth camera of its own, as a
// RealSense or Orbbec over plain UVC delivers it (nearest surface wins; what it cannot see is a
// hole). out/depth_camera.conf holds the keys that register it back (depth_camera.*).
bool unregister_depth(const std::string& in, const std::string& out, const std::string& config,
                      const DepthCameraShape& shape = DepthCameraShape());
// The depth of a sequence with every measured pixel moved by -1, 0 or +1 raw unit (from a fixed
// seed), less than any sensor's noise: tracking the copies of one sequence made with several
// seeds shows how much of an accuracy number is the one draw of noise the recording holds.
bool dither_depth(const std::string& in, const std::string& out, const std::string& config,
                  unsigned seed);
// The depth of a sequence as a structured-light sensor measures it, in the model the tracker
// weighs it by (config's depth.*): each pixel's disparity f b / z moved by Gaussian noise of
// depth.disparity_sigma and rounded to depth.disparity_quantum. With block_px > 1 each
// block_px square shares one draw, as the sensor's correlation window makes neighbours share
// their error, which averaging over pixels cannot remove. Meant for exact rendered depth:
// tracking it against these copies bounds what any refinement of the depths could give back.
bool sensor_noise_depth(const std::string& in, const std::string& out, const std::string& config,
                        unsigned seed, int block_px);
// The synthetic room on its diagonal path (parallax around the box) seen by the colour camera and
// by a depth camera of its own (shape; pinhole, no distortion): out/exact holds colour
// with the depth rendered in the colour camera, out/depth_camera the same colour with the depth
// camera's depth and the keys that register it. Prints how registration compares with the exact
// depth (pixels filled, errors, near occlusion edges apart).
// At most kTwoCameraFrames (3 s): later the glide takes the camera too near the box to track.
constexpr int kTwoCameraFrames = 90;
bool two_camera_sequence(const std::string& out, int frames, const DepthCameraShape& shape);
// A degenerate synthetic scene (SyntheticScene::Layout: "corridor" or "room"), 30 Hz.
bool degenerate_sequence(const std::string& out, const std::string& layout, int frames);

}  // namespace rgbdtam::testing

#pragma once
// A synthetic RGB-D world with exact ground truth: a room of textured planes and a box,
// ray-cast into a pinhole camera, one ray per pixel centre. The texture's edges are about a
// pixel and a half wide at these distances, so the images need no supersampling; depth is exact.

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "rgbdtam/core/camera.hpp"
#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/port/messages.hpp"

namespace rgbdtam::testing {

struct SyntheticFrame {
  std::vector<uint8_t> gray;
  std::vector<uint16_t> depth;  // depth_factor units; 0 = no measurement
  // The frame as a sensor source delivers it: frame index i of a sequence at fps.
  SensorFrame as_sensor_frame(const PinholeIntrinsics& k, int i, double fps) const {
    SensorFrame frame;
    frame.sequence = static_cast<uint32_t>(i);
    frame.timestamp_ns = static_cast<int64_t>(std::llround(i / fps * 1e9));
    frame.gray = gray.data();
    frame.depth = depth.data();
    frame.width_px = frame.depth_width_px = k.width_px;
    frame.height_px = frame.depth_height_px = k.height_px;
    return frame;
  }
};

struct SyntheticScene {
  PinholeIntrinsics camera{525.0, 525.0, 319.5, 239.5, 640, 480};
  double depth_factor = 5000.0;
  double max_depth_m = 6.0;  // beyond it the simulated sensor reports nothing
  bool with_box = true;
  double back_wall_z_m = 3.0;  // world z of the textured back wall

  SyntheticFrame render(const SE3& T_w_c) const;
  // Each row y from its own pose: a rolling shutter's rows are exposed one after another.
  SyntheticFrame render_rows(const std::function<SE3(int)>& T_w_c_of_row) const;
  // Frames i = 0 .. frames-1 at pose_at(i / fps), rendered once per test binary.
  const std::vector<SyntheticFrame>& render_path(int frames, double fps) const;
  // The same scene seen by a 320x240 camera, for tests where resolution does not matter.
  static SyntheticScene half_resolution() {
    SyntheticScene s;
    s.camera = {262.5, 262.5, 159.75, 119.75, 320, 240};
    return s;
  }
  // Smooth camera path: translation within ~10 cm and rotations within ~3 degrees.
  static SE3 pose_at(double t_s);
  // The camera of render_path(): pose_at, or with diagonal_path a steady 45 cm/s glide right
  // and up (so both edge orientations have parallax) with a slight forward drift, or with
  // pan_peak_deg_s > 0 a hand-held pan: yaw swinging +-35 degrees and a smaller pitch, peaking
  // at that rate, over a few centimetres of jitter.
  bool diagonal_path = false;
  double pan_peak_deg_s = 0.0;
  SE3 camera_at(double t_s) const;
  bool with_room = true;  // side walls and floor
  // Degenerate scenes for the health checks: plain planes with a few sharp-edged marks (doors,
  // posters), little else. A corridor (walls 0.6 and 0.9 m to the sides, floor 1 m below,
  // ceiling 0.5 m above) walked along at 2.4 m/s (8 cm a frame at 30 Hz) with the view swinging
  // +-5 degrees (up to 1 degree a frame); or a plain room (4 x 2.5 x 4 m) crossed on a circle
  // at the same speed while the view turns 1 degree a frame. Their own paths replace the ones
  // above.
  enum class Layout { kTexturedRoom, kCorridor, kPlainRoom };
  Layout layout = Layout::kTexturedRoom;
  // The box in the first view's lower-left corner instead of near the centre: as the camera
  // glides right and up it slides out of the corner, and the wall it covers meanwhile is wall
  // the first view never saw (in the centre it would hide a strip of the first keyframe's wall).
  bool box_in_corner = false;
};

}  // namespace rgbdtam::testing

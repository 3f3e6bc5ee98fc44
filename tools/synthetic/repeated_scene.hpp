#pragma once
// Scenes whose texture repeats, with exact ground truth, for the integrity checks: a wall of
// panels, tiles, brick or shelving beside a tiled floor, walked along sideways at 2-15 cm a
// frame, so that the image fits as well one texture period away and the depth of a wall and a
// floor says nothing about motion along both. Options add a structured-light sensor's noise
// and holes, a person crossing the view, and an auto-exposure step. Host side: allocates.

#include <cstdint>
#include <string>
#include <vector>

#include "synthetic_scene.hpp"

namespace rgbdtam::testing {

struct RepeatedScene {
  enum class Pattern { kPanels, kTiles, kBrick, kShelving };
  std::string name;
  Pattern wall = Pattern::kPanels;
  double period_m = 0.6;         // of the wall's pattern along the wall
  double wall_distance_m = 0.5;  // from the camera's path
  double floor_period_m = 0.3;   // square floor tiles
  // Lateral motion per frame, swinging between the two every four seconds.
  double min_step_m = 0.03, max_step_m = 0.08;
  double fps = 30.0;
  double max_turn_deg = 2.0;     // per frame, at the peak of the view's swing
  bool sensor_noise = false;     // disparity noise, its quantisation, and holes
  bool person = false;           // a person-sized box crossing between camera and wall
  int exposure_step_frame = -1;  // from this frame on the image is this much brighter
  double exposure_gain = 1.4;
  unsigned seed = 1;  // the structures' and the noise's
  PinholeIntrinsics camera{525.0, 525.0, 319.5, 239.5, 640, 480};
  double depth_factor = 5000.0;

  SE3 camera_at(int frame) const;
  SyntheticFrame render(int frame) const;
  // The scene with this name in family(), or false.
  static bool named(const std::string& name, RepeatedScene* out);
  // The family the integrity table and tests run: every pattern, periods from 5 cm to 1 m,
  // walls at 0.3-2 m, 10 and 30 Hz, with and without sensor noise, a person, an exposure step.
  static std::vector<RepeatedScene> family();
};

// Renders `frames` frames into a new TUM folder with the matching camera.conf.
bool repeated_sequence(const std::string& out, const RepeatedScene& scene, int frames);

}  // namespace rgbdtam::testing

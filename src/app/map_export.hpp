#pragma once
// Maps to plan with, from a map file: each remembered place's view (its inverse depth, at the
// view's resolution) cast from the place's pose, in a level frame whose z is up. A host- and
// board-side tool, run after the fact: it allocates freely.
//
// The level frame is x forward, y left, z up (ROS's REP 103), at the body of the first frame.
// Level comes from, in order: --up (gravity in the map's world frame, for example from an
// autopilot's attitude or a ground truth), else the board's link.T_b_c with its body taken as
// level at the first frame (--board), else a camera mounted looking forward (the boards'
// default link.T_b_c). The output says which.

#include <memory>
#include <vector>

#include "output_guard.hpp"
#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/core/status.hpp"
#include "rgbdtam/runtime/map_file.hpp"

namespace rgbdtam {

struct MapExportOptions {
  double resolution_m = 0.05;
  double max_range_m = 4.0;  // depth beyond it is not cast (the Kinect's reliable range)
  // Heights (m above the first frame's body) whose points are obstacles; lower points are
  // floor seen through free space, higher ones are ignored.
  double lowest_obstacle_m = -0.5, highest_obstacle_m = 0.5;
  const char* board_dir = nullptr;
  bool png = false;  // also <prefix>.png: the grid with the places' positions in mid grey
  bool has_up = false;
  Vector3d up_w = Vector3d::UnitZ();
};

// Takes argv[*i] (and its value) when it is one of the options above; false when it is not
// one. *error is set when it is one but its value is bad.
bool take_map_export_arg(int argc, char** argv, int* i, MapExportOptions* options, Status* error);

// What an export reads: the map, and the board file when --board names one.
std::vector<CommandFile> map_export_inputs(const char* map_path, const MapExportOptions& options);

// The largest map file the tools read (the format's own limit is far above any store).
constexpr size_t kMaxMapFileBytes = size_t{4} << 30;

// A map file's places, read whole (the map's own size, not a configuration's).
struct LoadedMap {
  MapFileInfo info;
  PlaceStore places;
};
Status read_map_for_export(const char* path, LoadedMap* map);

struct LevelFrame {
  SE3 T_l_w;  // level from the map's world
  char source[160] = "";
};
Status level_frame_of(const MapExportOptions& options, LevelFrame* out);

// Every view pixel with depth within max_range_m: visit(camera centre, point), both in the
// level frame.
template <typename Visit>
void for_each_map_point(const LoadedMap& map, const LevelFrame& level, double max_range_m,
                        Visit visit) {
  const PinholeIntrinsics k = View::intrinsics(map.info.camera);
  const float nearest_inverse_depth = static_cast<float>(1.0 / max_range_m);
  for (int i = 0; i < map.places.size(); ++i) {
    const PlaceRecord& place = map.places.in_order(i);
    const SE3 T_l_k = level.T_l_w * place.T_w_k;
    const Vector3d centre = T_l_k.translation();
    for (int v = 0; v < k.height_px; ++v) {
      for (int u = 0; u < k.width_px; ++u) {
        const float inverse_depth = place.view.inverse_depth.at(u, v) * kViewInverseDepthStep;
        if (inverse_depth < nearest_inverse_depth) continue;  // none, or out of range
        const double z = 1.0 / inverse_depth;
        const Vector3d p_k((u - k.cx_px) * z / k.fx_px, (v - k.cy_px) * z / k.fy_px, z);
        visit(centre, T_l_k * p_k);
      }
    }
  }
}

// The 2-D occupancy grid in ROS map_server's format: <prefix>.pgm (trinary: 0 occupied, 254
// free, 205 unknown, top row first) and <prefix>.yaml (image, resolution, origin of the
// lower-left cell, thresholds), and with options.png a preview <prefix>.png. Prints what it
// wrote.
Status export_occupancy_grid(const LoadedMap& map, const LevelFrame& level,
                             const MapExportOptions& options, const char* prefix);

}  // namespace rgbdtam

#pragma once
// A map file's views as a 3-D occupancy map in OctoMap's binary format (.bt), through Debian's
// liboctomap: each place's depth is one scan from the place's camera centre, so the rays clear
// the space they cross. Host tool only: the firmware never links OctoMap.

#include <cstddef>

#include "map_export.hpp"

namespace rgbdtam {

struct OctomapSummary {
  size_t nodes = 0, leaves = 0, occupied_leaves = 0;
  double lowest_m[3] = {0, 0, 0}, highest_m[3] = {0, 0, 0};  // the tree's bounding box
};

// Writes `path` beside itself and renames it into place.
Status export_octomap(const LoadedMap& map, const LevelFrame& level,
                      const MapExportOptions& options, const char* path, OctomapSummary* out);

}  // namespace rgbdtam

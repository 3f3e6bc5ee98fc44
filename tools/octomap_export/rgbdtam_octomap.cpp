// rgbdtam-octomap <map-file> <out.bt> [--resolution m] [--max-range m] [--board <folder> |
//                 --up x,y,z]
// A saved map as an OctoMap .bt file (octovis and OctoMap's tools open it), in the level frame
// of `rgbdtam map export` (map_export.hpp).
#include <cstdio>

#include "octomap_export.hpp"

int main(int argc, char** argv) {
  using namespace rgbdtam;
  MapExportOptions options;
  Status s;
  if (argc < 3) {
    s = Status::error(StatusCode::kInvalidArgument,
                      "usage: rgbdtam-octomap <map-file> <out.bt> [--resolution m] "
                      "[--max-range m] [--board <folder> | --up x,y,z]");
  }
  for (int i = 3; i < argc && s.is_ok(); ++i) {
    if (!take_map_export_arg(argc, argv, &i, &options, &s)) {
      s = Status::error(StatusCode::kInvalidArgument, "unknown argument %s", argv[i]);
    }
  }
  if (s.is_ok() && !outputs_are_safe("rgbdtam-octomap", {{"<out.bt>", argv[2]}},
                                     map_export_inputs(argv[1], options), {})) {
    return 2;
  }
  LoadedMap map;
  LevelFrame level;
  OctomapSummary summary;
  if (s.is_ok()) s = level_frame_of(options, &level);
  if (s.is_ok()) s = read_map_for_export(argv[1], &map);
  if (s.is_ok()) s = export_octomap(map, level, options, argv[2], &summary);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam-octomap: %s\n", s.message());
    return 1;
  }
  std::printf("map: %s, %d places\nlevel: %s\n", argv[1], map.places.size(), level.source);
  std::printf("octree: %s, resolution %.3f m, %zu nodes, %zu leaves (%zu occupied)\n", argv[2],
              options.resolution_m, summary.nodes, summary.leaves, summary.occupied_leaves);
  std::printf("bounds (m): x %.2f to %.2f, y %.2f to %.2f, z %.2f to %.2f\n", summary.lowest_m[0],
              summary.highest_m[0], summary.lowest_m[1], summary.highest_m[1], summary.lowest_m[2],
              summary.highest_m[2]);
  return 0;
}

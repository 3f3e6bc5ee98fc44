#include "octomap_export.hpp"

#include <octomap/octomap.h>

#include <cstdio>
#include <string>

namespace rgbdtam {
namespace {
octomap::point3d point(const Vector3d& p) {
  return octomap::point3d(static_cast<float>(p.x()), static_cast<float>(p.y()),
                          static_cast<float>(p.z()));
}
}  // namespace

Status export_octomap(const LoadedMap& map, const LevelFrame& level,
                      const MapExportOptions& options, const char* path, OctomapSummary* out) {
  octomap::OcTree tree(options.resolution_m);
  octomap::Pointcloud scan;
  Vector3d scan_origin(NAN, NAN, NAN);
  auto insert_scan = [&] {
    if (scan.size() > 0) tree.insertPointCloud(scan, point(scan_origin), options.max_range_m);
    scan.clear();
  };
  // for_each_map_point visits place by place: a new centre starts the next scan.
  for_each_map_point(map, level, options.max_range_m, [&](const Vector3d& c, const Vector3d& p) {
    if (c != scan_origin) {
      insert_scan();
      scan_origin = c;
    }
    scan.push_back(point(p));
  });
  insert_scan();
  if (tree.size() == 0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "the map's views hold no depth within --max-range %.1f m",
                         options.max_range_m);
  }
  tree.updateInnerOccupancy();
  tree.prune();
  const std::string partial = std::string(path) + ".partial";
  if (!tree.writeBinary(partial) || std::rename(partial.c_str(), path) != 0) {
    std::remove(partial.c_str());
    return Status::error(StatusCode::kIoError, "%s: cannot write the octree", path);
  }
  out->nodes = tree.size();
  out->leaves = tree.getNumLeafNodes();
  out->occupied_leaves = 0;
  for (auto leaf = tree.begin_leafs(); leaf != tree.end_leafs(); ++leaf) {
    out->occupied_leaves += tree.isNodeOccupied(*leaf) ? 1 : 0;
  }
  tree.getMetricMin(out->lowest_m[0], out->lowest_m[1], out->lowest_m[2]);
  tree.getMetricMax(out->highest_m[0], out->highest_m[1], out->highest_m[2]);
  return Status::ok();
}

}  // namespace rgbdtam

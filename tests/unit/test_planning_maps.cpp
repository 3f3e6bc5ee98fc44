// Maps to plan with from a map file of known geometry: one place looking forward at a wall 3 m
// away with the floor 1 m below. The grid (map_server's PGM and YAML) and the octree (read back
// through liboctomap) must hold the wall as occupied, the space before it as free, and what
// is behind it or outside the view as unknown.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "map_export.hpp"
#ifdef RGBDTAM_HAVE_OCTOMAP
#include <octomap/octomap.h>

#include "octomap_export.hpp"
#endif

namespace rgbdtam {
namespace {

// Mid-cell at 5 cm, so that the depth's quantisation cannot move them across a cell border.
constexpr double kWallM = 3.02, kFloorBelowM = 1.02;

class VectorSink : public ByteSink {
 public:
  bool write(const void* data, size_t size) override {
    const uint8_t* bytes = static_cast<const uint8_t*>(data);
    out.insert(out.end(), bytes, bytes + size);
    return true;
  }
  std::vector<uint8_t> out;
};

std::string temp_path(const char* name) {
  return ::testing::TempDir() + "planning_maps_" + std::to_string(::getpid()) + "_" + name;
}

// The map file of one place at the origin, its view filled with the scene's depth.
std::string write_scene_map() {
  const PinholeIntrinsics camera{525.0, 525.0, 319.5, 239.5, 640, 480};
  PlaceStore places;
  places.allocate(1, 4, 16, camera);
  {
    std::lock_guard<std::mutex> lock(places.mutex());
    PlaceRecord* p = places.begin_insert();
    p->keyframe_id = 0;
    const PinholeIntrinsics k = View::intrinsics(camera);
    for (int v = 0; v < k.height_px; ++v) {
      const double down = (v - k.cy_px) / k.fy_px;  // ray slope below the optical axis
      const double z = down > kFloorBelowM / kWallM ? kFloorBelowM / down : kWallM;
      for (int u = 0; u < k.width_px; ++u) {
        p->view.gray.at(u, v) = 128;
        p->view.inverse_depth.at(u, v) =
            static_cast<uint16_t>(std::lround(1.0 / (z * kViewInverseDepthStep)));
      }
    }
    places.commit();
  }
  MapFileInfo meta;
  meta.camera = camera;
  meta.vocabulary_words = 16;
  meta.next_keyframe_id = 1;
  FixedVector<LoopModule::Edge> edges;
  edges.reserve_once(1);
  VectorSink sink;
  EXPECT_TRUE(write_map(places, edges, meta, &sink).is_ok());
  const std::string path = temp_path("scene.map");
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(sink.out.data()),
             static_cast<std::streamsize>(sink.out.size()));
  return path;
}

struct Pgm {
  int width = 0, height = 0;
  std::string pixels;
  double resolution = 0, origin_x = 0, origin_y = 0;
  // The cell holding level-frame point (x, y); -1 outside the image.
  int at(double x, double y) const {
    const int col = static_cast<int>(std::floor((x - origin_x) / resolution));
    const int row = height - 1 - static_cast<int>(std::floor((y - origin_y) / resolution));
    if (col < 0 || col >= width || row < 0 || row >= height) return -1;
    return static_cast<uint8_t>(pixels[static_cast<size_t>(row) * width + col]);
  }
};

Pgm read_grid(const std::string& prefix) {
  Pgm g;
  std::ifstream pgm(prefix + ".pgm", std::ios::binary);
  std::string magic, comment_line;
  pgm >> magic;
  EXPECT_EQ(magic, "P5");
  pgm.get();
  if (pgm.peek() == '#') std::getline(pgm, comment_line);
  int max_value = 0;
  pgm >> g.width >> g.height >> max_value;
  EXPECT_EQ(max_value, 255);
  pgm.get();
  g.pixels.assign(std::istreambuf_iterator<char>(pgm), {});
  EXPECT_EQ(g.pixels.size(), static_cast<size_t>(g.width) * g.height);

  std::ifstream yaml(prefix + ".yaml");
  std::string line;
  bool image_named = false;
  while (std::getline(yaml, line)) {
    const std::string base = prefix.substr(prefix.rfind('/') + 1);
    image_named = image_named || line == "image: " + base + ".pgm";
    if (line.rfind("resolution: ", 0) == 0) g.resolution = std::stod(line.substr(12));
    if (line.rfind("origin: [", 0) == 0) {
      std::sscanf(line.c_str(), "origin: [%lf, %lf", &g.origin_x, &g.origin_y);
    }
  }
  EXPECT_TRUE(image_named) << "the YAML names the PGM beside it";
  return g;
}

TEST(PlanningMaps, GridHoldsTheWallOccupiedTheWayToItFreeAndTheRestUnknown) {
  const std::string map_path = write_scene_map();
  LoadedMap map;
  ASSERT_TRUE(read_map_for_export(map_path.c_str(), &map).is_ok());
  MapExportOptions options;
  options.lowest_obstacle_m = -0.8;  // the wall from just above the floor
  options.highest_obstacle_m = 0.8;
  LevelFrame level;
  ASSERT_TRUE(level_frame_of(options, &level).is_ok());
  EXPECT_NE(std::string(level.source).find("assumed"), std::string::npos) << level.source;
  const std::string prefix = temp_path("grid");
  ASSERT_TRUE(export_occupancy_grid(map, level, options, prefix.c_str()).is_ok());

  const Pgm g = read_grid(prefix);
  EXPECT_DOUBLE_EQ(g.resolution, 0.05);
  // Level frame: x forward, y left. The wall is at x = 3, seen over y within +-1.8 m.
  for (const double y : {-1.5, -0.5, 0.0, 0.5, 1.5}) {
    EXPECT_EQ(g.at(kWallM, y), 0) << "wall at y " << y;
    EXPECT_EQ(g.at(1.5, y * 0.4), 254) << "free on the way, y " << y * 0.4;
    EXPECT_EQ(g.at(2.6, y), 254) << "floor seen before the wall, y " << y;
  }
  EXPECT_EQ(g.at(0.5, 1.5), 205) << "outside the view";
  const int behind = g.at(kWallM + 0.3, 0.0);  // unknown, or past the grid's edge
  EXPECT_TRUE(behind == 205 || behind == -1) << "behind the wall: " << behind;
  std::remove(map_path.c_str());
}

TEST(PlanningMaps, GravityGivenAsUpMatchesTheMountingItDescribes) {
  MapExportOptions mounting, up;
  up.has_up = true;
  up.up_w = Vector3d(0, -1, 0);  // a forward camera's up is its -y
  LevelFrame a, b;
  ASSERT_TRUE(level_frame_of(mounting, &a).is_ok());
  ASSERT_TRUE(level_frame_of(up, &b).is_ok());
  EXPECT_LT((a.T_l_w.rotation() - b.T_l_w.rotation()).norm(), 1e-9);
  EXPECT_NE(std::string(b.source).find("--up"), std::string::npos) << b.source;
  // A camera pitched 30 degrees down: the level frame's z is gravity's, not the camera's.
  const double pitch = 30.0 * M_PI / 180.0;
  up.up_w = Vector3d(0, -std::cos(pitch), std::sin(pitch));
  ASSERT_TRUE(level_frame_of(up, &b).is_ok());
  EXPECT_LT((b.T_l_w.rotation() * up.up_w - Vector3d::UnitZ()).norm(), 1e-9);
  EXPECT_GT((b.T_l_w.rotation() * Vector3d::UnitZ()).x(), 0.8) << "x stays forward";
}

TEST(PlanningMaps, BadInputIsRefusedWithTheReason) {
  const std::string garbage = temp_path("garbage.map");
  std::ofstream(garbage) << "not a map";
  LoadedMap map;
  const Status s = read_map_for_export(garbage.c_str(), &map);
  EXPECT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("not an rgbdtam map file"), std::string::npos)
      << s.message();
  std::remove(garbage.c_str());

  const char* bad[][2] = {{"--heights", "1,0"},
                          {"--resolution", "0"},
                          {"--up", "0,0,0"},
                          {"--max-range", "nan"},
                          {"--heights", "1,2,3"}};
  for (const auto& arg : bad) {
    char* argv[] = {const_cast<char*>(arg[0]), const_cast<char*>(arg[1])};
    int i = 0;
    MapExportOptions options;
    Status error;
    EXPECT_TRUE(take_map_export_arg(2, argv, &i, &options, &error));
    EXPECT_FALSE(error.is_ok()) << arg[0] << " " << arg[1];
  }
}

#ifdef RGBDTAM_HAVE_OCTOMAP
TEST(PlanningMaps, OctreeReadBackByOctomapHoldsTheWall) {
  const std::string map_path = write_scene_map();
  LoadedMap map;
  ASSERT_TRUE(read_map_for_export(map_path.c_str(), &map).is_ok());
  MapExportOptions options;
  LevelFrame level;
  ASSERT_TRUE(level_frame_of(options, &level).is_ok());
  const std::string path = temp_path("scene.bt");
  OctomapSummary summary;
  ASSERT_TRUE(export_octomap(map, level, options, path.c_str(), &summary).is_ok());

  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(path));
  EXPECT_EQ(tree.size(), summary.nodes);
  EXPECT_DOUBLE_EQ(tree.getResolution(), options.resolution_m);
  EXPECT_GT(summary.occupied_leaves, 0u);
  auto occupied = [&](double x, double y, double z) {
    const octomap::OcTreeNode* node = tree.search(x, y, z);
    return node == nullptr ? -1 : tree.isNodeOccupied(node) ? 1 : 0;
  };
  EXPECT_EQ(occupied(kWallM, 0.0, 0.0), 1);
  EXPECT_EQ(occupied(kWallM, 1.0, 0.5), 1);
  // The floor, seen at a grazing angle: rays to its far points cross the voxels of nearer ones,
  // and a voxel whose row of the view ends in another stays free; most hold an end.
  int floor_voxels = 0, floor_occupied = 0;
  for (double x = 2.325; x < 2.95; x += 0.05, ++floor_voxels) {
    floor_occupied += occupied(x, 0.025, -kFloorBelowM) == 1;
  }
  EXPECT_GE(floor_occupied, floor_voxels * 3 / 4) << "of " << floor_voxels << " floor voxels";
  EXPECT_EQ(occupied(1.5, 0.0, 0.0), 0);
  EXPECT_EQ(occupied(kWallM + 0.5, 0.0, 0.0), -1) << "behind the wall";
  std::remove(path.c_str());
  std::remove(map_path.c_str());
}
#endif

}  // namespace
}  // namespace rgbdtam

// The map export of a real replay opens in Open3D (Debian's python3-open3d) and shows the desk:
// tools/check_map.py finds a table-top plane holding a quarter of the points or more.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "replay_runner.hpp"
#include "rgbdtam/hal/ply_map_writer.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

TEST(MapExport, ClipMapOpensInOpen3dAndShowsTheDesk) {
  const std::string ply_path = testing::make_temp_dir("map_export") + "/clip_map.ply";
  PlyMapWriter ply;
  ASSERT_TRUE(ply.open(ply_path.c_str()).is_ok());
  const auto out = testing::replay_and_evaluate(testing::source_path("data/tum_fr1_xyz_clip"),
                                                testing::source_path("config/tum_fr1.conf"),
                                                {"map.enabled=true"}, &ply);
  ASSERT_TRUE(out.ran);
  ASSERT_TRUE(ply.close().is_ok());
  EXPECT_GT(ply.points(), 10000u);
  const std::string command = "/usr/bin/python3 " + testing::source_path("tools/check_map.py") +
                              " " + ply_path + " --expect-desk";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
}

}  // namespace
}  // namespace rgbdtam

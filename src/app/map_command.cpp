#include "map_command.hpp"

#include <time.h>

#include <cstdio>
#include <cstring>

#include "config_files.hpp"
#include "map_export.hpp"
#include "output_guard.hpp"
#include "rgbdtam/runtime/map_file.hpp"

namespace rgbdtam {
namespace {

int info_command(const char* path) {
  std::unique_ptr<uint8_t[]> data;
  size_t size = 0;
  MapFileInfo m;
  Status s = read_binary_file(path, kMaxMapFileBytes, &data, &size);
  if (s.is_ok()) s = read_map_info(data.get(), size, &m);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam map info: %s: %s\n", path, s.message());
    return 1;
  }
  const time_t written_s = static_cast<time_t>(m.written_unix_ns / 1000000000);
  tm utc;
  char when[32] = "?";
  if (gmtime_r(&written_s, &utc) != nullptr)
    std::strftime(when, sizeof(when), "%Y-%m-%d %H:%M:%S UTC", &utc);
  std::printf("map file: %s (format version %u, %.1f MB)\n", path, m.version,
              static_cast<double>(m.file_bytes) / (1 << 20));
  std::printf("written: %s by %s\n", when, m.written_by);
  std::printf("places: %u (at most %u features each), graph edges: %u, next keyframe id %u\n",
              m.places, m.most_features, m.edges, m.next_keyframe_id);
  std::printf(
      "extent of the places (world frame, m): x %.2f to %.2f, y %.2f to %.2f, z %.2f to %.2f\n",
      m.lowest_m[0], m.highest_m[0], m.lowest_m[1], m.highest_m[1], m.lowest_m[2], m.highest_m[2]);
  std::printf("camera: %dx%d, fx %.3f fy %.3f cx %.3f cy %.3f; views %ux%u\n", m.camera.width_px,
              m.camera.height_px, m.camera.fx_px, m.camera.fy_px, m.camera.cx_px, m.camera.cy_px,
              m.view_width_px, m.view_height_px);
  std::printf("vocabulary: %u words, checksum %08x\n", m.vocabulary_words, m.vocabulary_checksum);
  return 0;
}
// argv: <file> --grid <prefix> [export options]
int export_command(int argc, char** argv) {
  const char* grid = nullptr;
  MapExportOptions options;
  Status s;
  for (int i = 1; i < argc && s.is_ok(); ++i) {
    if (std::strcmp(argv[i], "--grid") == 0 && i + 1 < argc) {
      grid = argv[++i];
    } else if (std::strcmp(argv[i], "--png") == 0) {
      options.png = true;
    } else if (!take_map_export_arg(argc, argv, &i, &options, &s)) {
      s = Status::error(StatusCode::kInvalidArgument, "unknown argument %s", argv[i]);
    }
  }
  if (s.is_ok() && grid == nullptr) {
    s = Status::error(StatusCode::kInvalidArgument, "--grid <prefix> is required");
  }
  if (s.is_ok()) {
    const std::string prefix = grid;
    const std::vector<CommandFile> outputs = {{"--grid", prefix + ".pgm"},
                                              {"--grid", prefix + ".yaml"},
                                              {"--png", options.png ? prefix + ".png" : ""}};
    if (!outputs_are_safe("rgbdtam map export", outputs, map_export_inputs(argv[0], options), {})) {
      return 2;
    }
  }
  LoadedMap map;
  LevelFrame level;
  if (s.is_ok()) s = level_frame_of(options, &level);
  if (s.is_ok()) s = read_map_for_export(argv[0], &map);
  if (s.is_ok()) {
    std::printf("map: %s, %d places\nlevel: %s\n", argv[0], map.places.size(), level.source);
    s = export_occupancy_grid(map, level, options, grid);
  }
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam map export: %s\n", s.message());
    return 1;
  }
  return 0;
}

constexpr const char* kUsage =
    "usage: rgbdtam map info <file>\n"
    "       rgbdtam map export <file> --grid <prefix> [--png] [--resolution m]\n"
    "                          [--heights low,high] [--max-range m]\n"
    "                          [--board <folder> | --up x,y,z]\n";
}  // namespace

int map_command(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[0], "info") == 0) return info_command(argv[1]);
  if (argc >= 2 && std::strcmp(argv[0], "export") == 0) return export_command(argc - 1, argv + 1);
  std::fprintf(stderr, "%s", kUsage);
  return 2;
}

}  // namespace rgbdtam

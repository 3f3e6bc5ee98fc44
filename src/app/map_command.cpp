#include "map_command.hpp"

#include <time.h>

#include <cstdio>
#include <cstring>

#include "config_files.hpp"
#include "rgbdtam/runtime/map_file.hpp"

namespace rgbdtam {
namespace {
constexpr size_t kMaxMapFileBytes = size_t{4} << 30;

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
}  // namespace

int map_command(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[0], "info") == 0) return info_command(argv[1]);
  std::fprintf(stderr, "usage: rgbdtam map info <file>\n");
  return 2;
}

}  // namespace rgbdtam

#include "map_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "config_files.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/png_encoder.hpp"
#include "run_job.hpp"

namespace rgbdtam {
namespace {
constexpr long kMostCells = 1L << 26;
// map_saver's trinary values and thresholds (ROS navigation's map_saver.cpp).
constexpr uint8_t kOccupied = 0, kFree = 254, kUnknown = 205;
constexpr double kOccupiedThreshold = 0.65, kFreeThreshold = 0.196;
// A cell is a column of the height band. A ray crossing it shows it free at one height only,
// so an obstacle seen in it wins over any number of rays; this many points, not one stray.
constexpr uint32_t kObstaclePoints = 3;

bool parse_number(const char* text, double* out) {
  char* end = nullptr;
  *out = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(*out);
}

// "a,b" or "a,b,c": count finite numbers.
bool parse_numbers(const char* text, int count, double* out) {
  char copy[128];
  if (std::snprintf(copy, sizeof(copy), "%s", text) >= static_cast<int>(sizeof(copy))) return false;
  char* rest = copy;
  for (int n = 0; n < count; ++n) {
    char* comma = std::strchr(rest, ',');
    if ((comma == nullptr) != (n == count - 1)) return false;
    if (comma != nullptr) *comma = '\0';
    if (!parse_number(rest, &out[n])) return false;
    rest = comma + 1;
  }
  return true;
}

// The body's FRD axes as the level frame's FLU ones.
SE3 flu_from_frd() { return SE3(Eigen::Quaterniond(0, 1, 0, 0), Vector3d::Zero()); }

// x along the camera's forward direction made horizontal, z up.
SE3 level_from_up(const Vector3d& up_w) {
  const Vector3d z = up_w.normalized();
  Vector3d x = Vector3d::UnitZ() - z * z.z();
  if (x.norm() < 1e-6) x = Vector3d::UnitX() - z * z.x();  // looking straight up or down
  x.normalize();
  Matrix3d R_l_w;
  R_l_w.row(0) = x.transpose();
  R_l_w.row(1) = z.cross(x).transpose();
  R_l_w.row(2) = z.transpose();
  return SE3(Eigen::Quaterniond(R_l_w), Vector3d::Zero());
}

struct Cell {
  uint32_t hits = 0, misses = 0;
};

class Grid {
 public:
  Grid(double min_x, double min_y, int width, int height, double resolution)
      : min_x_(min_x),
        min_y_(min_y),
        width_(width),
        height_(height),
        resolution_(resolution),
        cells_(static_cast<size_t>(width) * height) {}
  int column(double x) const { return static_cast<int>(std::floor((x - min_x_) / resolution_)); }
  int row(double y) const { return static_cast<int>(std::floor((y - min_y_) / resolution_)); }
  Cell& at(int c, int r) { return cells_[static_cast<size_t>(r) * width_ + c]; }
  const Cell& at(int c, int r) const { return cells_[static_cast<size_t>(r) * width_ + c]; }
  // The cells the ray from cell (c0, r0) crosses before cell (c1, r1) (Bresenham) are seen free.
  void clear_ray(int c0, int r0, int c1, int r1) {
    const int dc = std::abs(c1 - c0), dr = -std::abs(r1 - r0);
    const int sc = c0 < c1 ? 1 : -1, sr = r0 < r1 ? 1 : -1;
    int error = dc + dr;
    while (c0 != c1 || r0 != r1) {
      ++at(c0, r0).misses;
      const int e2 = 2 * error;
      if (e2 >= dr) {
        error += dr;
        c0 += sc;
      }
      if (e2 <= dc) {
        error += dc;
        r0 += sr;
      }
    }
  }
  uint8_t value(int c, int r) const {
    const Cell& cell = at(c, r);
    if (cell.hits >= kObstaclePoints) return kOccupied;
    return cell.misses > 0 ? kFree : kUnknown;
  }
  double min_x() const { return min_x_; }
  double min_y() const { return min_y_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  double min_x_, min_y_;
  int width_, height_;
  double resolution_;
  std::vector<Cell> cells_;
};

Status write_file(const char* path, const char* text, size_t size) {
  char buffer[1 << 12];
  OutputFile file;
  RGBDTAM_RETURN_IF_ERROR(file.open(path, buffer, sizeof(buffer)));
  RGBDTAM_RETURN_IF_ERROR(file.check(std::fwrite(text, 1, size, file.stream()) == size));
  return file.commit();
}
}  // namespace

std::vector<CommandFile> map_export_inputs(const char* map_path, const MapExportOptions& options) {
  std::vector<CommandFile> inputs = {{"the map", map_path}};
  if (options.board_dir != nullptr) {
    inputs.push_back({"--board", std::string(options.board_dir) + "/board.conf"});
  }
  return inputs;
}

bool take_map_export_arg(int argc, char** argv, int* i, MapExportOptions* o, Status* error) {
  const char* flag = argv[*i];
  const bool known = std::strcmp(flag, "--resolution") == 0 ||
                     std::strcmp(flag, "--max-range") == 0 || std::strcmp(flag, "--heights") == 0 ||
                     std::strcmp(flag, "--board") == 0 || std::strcmp(flag, "--up") == 0;
  if (!known) return false;
  if (*i + 1 >= argc) {
    *error = Status::error(StatusCode::kInvalidArgument, "%s needs a value", flag);
    return true;
  }
  const char* value = argv[++*i];
  double v[3] = {0, 0, 0};
  bool ok = true;
  if (std::strcmp(flag, "--resolution") == 0) {
    ok = parse_number(value, &o->resolution_m) && o->resolution_m >= 0.005 && o->resolution_m <= 10;
  } else if (std::strcmp(flag, "--max-range") == 0) {
    ok = parse_number(value, &o->max_range_m) && o->max_range_m > 0.2 && o->max_range_m <= 100;
  } else if (std::strcmp(flag, "--heights") == 0) {
    ok = parse_numbers(value, 2, v) && v[0] < v[1];
    o->lowest_obstacle_m = v[0];
    o->highest_obstacle_m = v[1];
  } else if (std::strcmp(flag, "--board") == 0) {
    o->board_dir = value;
  } else {
    ok = parse_numbers(value, 3, v) && Vector3d(v[0], v[1], v[2]).norm() > 1e-6;
    o->up_w = Vector3d(v[0], v[1], v[2]);
    o->has_up = true;
  }
  if (!ok) {
    *error = Status::error(StatusCode::kInvalidArgument,
                           "%s %s: expected --resolution 0.005..10 (m), --max-range 0.2..100 "
                           "(m), --heights low,high (m, low < high), --up x,y,z (not zero)",
                           flag, value);
  }
  return true;
}

Status read_map_for_export(const char* path, LoadedMap* map) {
  std::unique_ptr<uint8_t[]> data;
  size_t size = 0;
  Status s = read_binary_file(path, kMaxMapFileBytes, &data, &size);
  if (s.is_ok()) s = read_map_places(data.get(), size, &map->places, &map->info);
  if (!s.is_ok()) return Status::error(s.code(), "%s: %s", path, s.message());
  return s;
}

Status level_frame_of(const MapExportOptions& options, LevelFrame* out) {
  if (options.has_up) {
    out->T_l_w = level_from_up(options.up_w);
    std::snprintf(out->source, sizeof(out->source),
                  "gravity given by --up (%.3f, %.3f, %.3f in the map's world frame)",
                  options.up_w.x(), options.up_w.y(), options.up_w.z());
    return Status::ok();
  }
  // Camera z forward, x right, y down: the shipped boards' mounting.
  SE3 T_b_c(Eigen::Quaterniond(0.5, 0.5, 0.5, 0.5), Vector3d::Zero());
  const char* whose = "a camera looking forward (the shipped boards' mounting)";
  if (options.board_dir != nullptr) {
    Board board;
    RGBDTAM_RETURN_IF_ERROR(load_board(options.board_dir, &board));
    T_b_c = board.T_b_c;
    whose = "the board's link.T_b_c";
  }
  out->T_l_w = flu_from_frd() * T_b_c;
  std::snprintf(out->source, sizeof(out->source),
                "assumed: the body of %s at the first frame, taken as level (the map "
                "records no autopilot attitude)",
                whose);
  return Status::ok();
}

Status export_occupancy_grid(const LoadedMap& map, const LevelFrame& level,
                             const MapExportOptions& options, const char* prefix) {
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for_each_map_point(map, level, options.max_range_m, [&](const Vector3d& c, const Vector3d& p) {
    for (int k = 0; k < 2; ++k) {
      lo[k] = std::min({lo[k], c[k], p[k]});
      hi[k] = std::max({hi[k], c[k], p[k]});
    }
  });
  if (!(lo[0] <= hi[0])) {
    return Status::error(StatusCode::kInvalidArgument,
                         "the map's views hold no depth within --max-range %.1f m",
                         options.max_range_m);
  }
  const double r = options.resolution_m;
  const long width = static_cast<long>(std::ceil((hi[0] - lo[0]) / r)) + 2;
  const long height = static_cast<long>(std::ceil((hi[1] - lo[1]) / r)) + 2;
  if (width * height > kMostCells) {
    return Status::error(StatusCode::kOutOfRange,
                         "a grid of %ldx%ld cells at %.3f m: raise --resolution or lower "
                         "--max-range",
                         width, height, r);
  }
  Grid grid(lo[0] - r, lo[1] - r, static_cast<int>(width), static_cast<int>(height), r);
  long obstacles = 0, floor = 0;
  for_each_map_point(map, level, options.max_range_m, [&](const Vector3d& c, const Vector3d& p) {
    const int c1 = grid.column(p.x()), r1 = grid.row(p.y());
    if (p.z() > options.highest_obstacle_m) return;  // above the robot: says nothing of its way
    grid.clear_ray(grid.column(c.x()), grid.row(c.y()), c1, r1);
    if (p.z() >= options.lowest_obstacle_m) {
      ++grid.at(c1, r1).hits;
      ++obstacles;
    } else {
      ++grid.at(c1, r1).misses;
      ++floor;
    }
  });

  std::vector<uint8_t> image;  // the image's top row is the map's +y
  long counts[3] = {0, 0, 0};  // occupied, free, unknown
  for (int row = grid.height() - 1; row >= 0; --row) {
    for (int col = 0; col < grid.width(); ++col) {
      const uint8_t v = grid.value(col, row);
      image.push_back(v);
      ++counts[v == kOccupied ? 0 : v == kFree ? 1 : 2];
    }
  }
  char header[128];
  const int header_size =
      std::snprintf(header, sizeof(header), "P5\n# rgbdtam map export %.3f m/pix\n%d %d\n255\n", r,
                    grid.width(), grid.height());
  std::vector<uint8_t> pgm(header, header + header_size);
  pgm.insert(pgm.end(), image.begin(), image.end());
  char pgm_path[PATH_MAX], yaml_path[PATH_MAX], png_path[PATH_MAX];
  std::snprintf(pgm_path, sizeof(pgm_path), "%s.pgm", prefix);
  std::snprintf(yaml_path, sizeof(yaml_path), "%s.yaml", prefix);
  std::snprintf(png_path, sizeof(png_path), "%s.png", prefix);
  const char* slash = std::strrchr(pgm_path, '/');
  char yaml[512];
  const int yaml_size = std::snprintf(
      yaml, sizeof(yaml),
      "image: %s\nmode: trinary\nresolution: %.6f\norigin: [%.6f, %.6f, 0.0]\nnegate: 0\n"
      "occupied_thresh: %.3f\nfree_thresh: %.3f\n",
      slash != nullptr ? slash + 1 : pgm_path, r, grid.min_x(), grid.min_y(), kOccupiedThreshold,
      kFreeThreshold);
  RGBDTAM_RETURN_IF_ERROR(
      write_file(pgm_path, reinterpret_cast<const char*>(pgm.data()), pgm.size()));
  RGBDTAM_RETURN_IF_ERROR(write_file(yaml_path, yaml, static_cast<size_t>(yaml_size)));
  if (options.png) {
    constexpr uint8_t kPlace = 128;
    for (int i = 0; i < map.places.size(); ++i) {
      const Vector3d c = level.T_l_w * map.places.in_order(i).T_w_k.translation();
      const int col = grid.column(c.x()), row = grid.height() - 1 - grid.row(c.y());
      image[static_cast<size_t>(row) * grid.width() + col] = kPlace;
    }
    // Cells as squares of pixels, so that a small map is large enough to look at.
    constexpr int kPreviewSide = 512;
    const int scale = std::max(1, kPreviewSide / std::max(grid.width(), grid.height()));
    const int w = grid.width() * scale, h = grid.height() * scale;
    std::vector<uint8_t> preview(static_cast<size_t>(w) * h);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        preview[static_cast<size_t>(y) * w + x] =
            image[static_cast<size_t>(y / scale) * grid.width() + x / scale];
      }
    }
    PngEncoder png;
    png.allocate(w, h);
    RGBDTAM_RETURN_IF_ERROR(png.encode_gray8(preview.data(), w, h));
    RGBDTAM_RETURN_IF_ERROR(
        write_file(png_path, reinterpret_cast<const char*>(png.data()), png.size()));
  }
  std::printf("grid: %s and %s%s%s, %dx%d cells of %.3f m, origin (%.2f, %.2f) m\n", pgm_path,
              yaml_path, options.png ? " and " : "", options.png ? png_path : "", grid.width(),
              grid.height(), r, grid.min_x(), grid.min_y());
  std::printf(
      "cells: %ld occupied, %ld free, %ld unknown; points: %ld obstacles (%.2f to %.2f m "
      "high), %ld floor below them\n",
      counts[0], counts[1], counts[2], obstacles, options.lowest_obstacle_m,
      options.highest_obstacle_m, floor);
  return Status::ok();
}

}  // namespace rgbdtam

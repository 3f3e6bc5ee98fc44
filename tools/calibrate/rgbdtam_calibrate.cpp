// Per-unit calibration of a camera whose depth comes from a camera of its own (docs/sensors.md,
// "Calibrating a unit"):
//   rgbdtam-calibrate <colour-dir> <depth-camera-dir> --board COLSxROWS --square-m S
//                     [--min-views N] [--out keys.conf]
// Each folder holds PNG (or PGM) views of a checkerboard (COLS x ROWS inner corners, squares S
// metres), taken in pairs: the n-th colour image (in name order) and the n-th depth camera image
// (its infrared, pixel-aligned with its depth) show the board in the same place. Prints the camera
// config's keys (or writes them to a new file) with the reprojection errors. Host tool.
#include <opencv2/imgcodecs.hpp>

#include <sys/stat.h>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "calibration.hpp"

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: rgbdtam-calibrate <colour-dir> <depth-camera-dir> --board COLSxROWS "
               "--square-m S [--min-views N] [--out keys.conf]\n");
  return 2;
}

bool load_views(const std::string& dir, std::vector<cv::Mat>* out, std::string* error) {
  std::vector<cv::String> names, pgm;
  cv::glob(dir + "/*.png", names, false);
  cv::glob(dir + "/*.pgm", pgm, false);  // a raw GREY frame with a PGM header
  names.insert(names.end(), pgm.begin(), pgm.end());
  std::sort(names.begin(), names.end());
  if (names.empty()) {
    *error = dir + ": no .png or .pgm views";
    return false;
  }
  for (const cv::String& name : names) {
    cv::Mat gray = cv::imread(name, cv::IMREAD_GRAYSCALE);
    if (gray.empty()) {
      *error = name + ": not a readable image";
      return false;
    }
    if (!out->empty() && gray.size() != out->front().size()) {
      *error = name + ": another size than the folder's first view";
      return false;
    }
    out->push_back(gray);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return usage();
  const std::string colour_dir = argv[1], depth_dir = argv[2];
  rgbdtam::Checkerboard board;
  int min_views = 8;
  const char* out_path = nullptr;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) return usage();
    const char* v = argv[++i];
    if (a == "--board") {
      int cols = 0, rows = 0;
      char x = 0;
      if (std::sscanf(v, "%d%c%d", &cols, &x, &rows) != 3 || x != 'x' || cols < 3 || rows < 3) {
        std::fprintf(stderr,
                     "rgbdtam-calibrate: --board '%s' is not COLSxROWS (inner corners, "
                     "each at least 3)\n",
                     v);
        return 2;
      }
      board.inner_corners = cv::Size(cols, rows);
    } else if (a == "--square-m") {
      board.square_m = std::atof(v);
      if (!(board.square_m > 0.0 && board.square_m < 1.0)) {
        std::fprintf(stderr,
                     "rgbdtam-calibrate: --square-m '%s' is not a square's side in "
                     "metres (above 0, below 1: not mm?)\n",
                     v);
        return 2;
      }
    } else if (a == "--min-views") {
      min_views = std::atoi(v);
      if (min_views < 3) return usage();
    } else if (a == "--out") {
      out_path = v;
    } else {
      return usage();
    }
  }
  if (board.inner_corners.area() == 0 || board.square_m <= 0.0) return usage();
  struct stat st;
  if (out_path != nullptr && ::stat(out_path, &st) == 0) {
    std::fprintf(stderr, "rgbdtam-calibrate: %s exists: name a new file\n", out_path);
    return 1;
  }
  std::vector<cv::Mat> colour, depth;
  std::string error;
  rgbdtam::RgbdCalibration result;
  if (!load_views(colour_dir, &colour, &error) || !load_views(depth_dir, &depth, &error) ||
      !rgbdtam::calibrate_rgbd(colour, depth, board, min_views, &result, &error)) {
    std::fprintf(stderr, "rgbdtam-calibrate: %s\n", error.c_str());
    return 1;
  }
  const std::string keys = rgbdtam::config_keys(result);
  if (out_path == nullptr) {
    std::fputs(keys.c_str(), stdout);
    return 0;
  }
  std::ofstream file(out_path);
  file << keys;
  file.close();
  if (!file) {
    std::fprintf(stderr, "rgbdtam-calibrate: writing %s failed\n", out_path);
    std::remove(out_path);
    return 1;
  }
  std::fputs(keys.substr(0, keys.find('\n') + 1).c_str(), stdout);
  return 0;
}

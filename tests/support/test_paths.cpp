#include "test_paths.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>

namespace rgbdtam::testing {

std::string source_path(const std::string& relative) {
  // On a board (tools/hil/run.py) the source tree's data is copied elsewhere.
  const char* env = std::getenv("RGBDTAM_SOURCE_DIR");
  return std::string(env != nullptr ? env : RGBDTAM_SOURCE_DIR) + "/" + relative;
}

namespace {
std::string if_sequence(const std::string& path) {
  struct stat st;
  return ::stat((path + "/rgb.txt").c_str(), &st) == 0 ? path : std::string();
}
std::string fr1_xyz_path() {
  const char* env = std::getenv("RGBDTAM_TUM_FR1_XYZ");
  return env != nullptr ? env : RGBDTAM_TUM_FR1_XYZ;
}
}  // namespace

std::string full_fr1_xyz() { return if_sequence(fr1_xyz_path()); }

std::string fr3_teddy_200() { return if_sequence(fr1_xyz_path() + "/../fr3_teddy_200"); }

std::string make_temp_dir(const char* tag) {
  std::string pattern = std::string("/tmp/rgbdtam_") + tag + "_XXXXXX";
  char* dir = ::mkdtemp(pattern.data());
  return dir != nullptr ? std::string(dir) : std::string();
}

}  // namespace rgbdtam::testing

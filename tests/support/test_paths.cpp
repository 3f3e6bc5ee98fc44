#include "test_paths.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>

namespace rgbdtam::testing {

std::string source_path(const std::string& relative) {
  return std::string(RGBDTAM_SOURCE_DIR) + "/" + relative;
}

std::string full_fr1_xyz() {
  const char* env = std::getenv("RGBDTAM_TUM_FR1_XYZ");
  const std::string path = env != nullptr ? env : RGBDTAM_TUM_FR1_XYZ;
  struct stat st;
  return ::stat((path + "/rgb.txt").c_str(), &st) == 0 ? path : std::string();
}

std::string make_temp_dir(const char* tag) {
  std::string pattern = std::string("/tmp/rgbdtam_") + tag + "_XXXXXX";
  char* dir = ::mkdtemp(pattern.data());
  return dir != nullptr ? std::string(dir) : std::string();
}

}  // namespace rgbdtam::testing

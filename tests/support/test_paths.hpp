#pragma once
#include <string>

namespace rgbdtam::testing {
// The repository's own files (config/, data/).
std::string source_path(const std::string& relative);
// The full fr1_xyz sequence; empty when this machine does not have it.
std::string full_fr1_xyz();
// The first 200 frames of fr3_teddy, beside fr1_xyz in the shared TUM data; empty when absent.
std::string fr3_teddy_200();
// A fresh, empty folder for one test's files.
std::string make_temp_dir(const char* tag);
}  // namespace rgbdtam::testing

#include "output_guard.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <climits>
#include <cstdio>
#include <cstdlib>

namespace rgbdtam {
namespace {

std::string folder_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : path.substr(0, std::max<size_t>(slash, 1));
}

// Where an output will be: its folder resolved (links, "..") and its name; empty when the
// folder does not exist (the open will say so).
std::string resolved_output(const std::string& path) {
  char real[PATH_MAX];
  if (::realpath(folder_of(path).c_str(), real) == nullptr) return "";
  return std::string(real) + "/" + path.substr(path.find_last_of('/') + 1);
}

bool same_file(const std::string& a, const struct stat& b) {
  struct stat st;
  return ::stat(a.c_str(), &st) == 0 && st.st_dev == b.st_dev && st.st_ino == b.st_ino;
}

}  // namespace

bool outputs_are_safe(const char* command, const std::vector<CommandFile>& outputs,
                      const std::vector<CommandFile>& inputs,
                      const std::vector<std::string>& input_folders) {
  for (size_t i = 0; i < outputs.size(); ++i) {
    const CommandFile& o = outputs[i];
    if (o.path.empty()) continue;
    const std::string resolved = resolved_output(o.path);
    for (size_t j = 0; j < i; ++j) {
      if (!outputs[j].path.empty() && !resolved.empty() &&
          resolved == resolved_output(outputs[j].path)) {
        std::fprintf(stderr, "%s: %s and %s name one file (%s): give each its own\n", command,
                     outputs[j].option.c_str(), o.option.c_str(), o.path.c_str());
        return false;
      }
    }
    struct stat out;
    if (::stat(o.path.c_str(), &out) != 0) continue;  // a new file replaces nothing
    for (const CommandFile& input : inputs) {
      if (input.path.empty() || input.replaced_by == o.option) continue;
      if (same_file(input.path, out)) {
        std::fprintf(stderr, "%s: %s %s is an input of this run (%s)\n", command, o.option.c_str(),
                     o.path.c_str(), input.path.c_str());
        return false;
      }
    }
    struct stat dir;
    if (::stat(folder_of(o.path).c_str(), &dir) != 0) continue;
    for (const std::string& folder : input_folders) {
      if (same_file(folder, dir)) {
        std::fprintf(stderr, "%s: %s %s would replace one of the inputs in %s\n", command,
                     o.option.c_str(), o.path.c_str(), folder.c_str());
        return false;
      }
    }
  }
  return true;
}

void add_sequence_inputs(const std::string& sequence, std::vector<CommandFile>* inputs,
                         std::vector<std::string>* folders) {
  for (const char* list : {"rgb.txt", "depth.txt", "groundtruth.txt"}) {
    inputs->push_back({sequence + "/" + list, sequence + "/" + list});
  }
  folders->push_back(sequence + "/rgb");
  folders->push_back(sequence + "/depth");
}

}  // namespace rgbdtam

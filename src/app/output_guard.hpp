#pragma once
// Every command checks its outputs before it reads anything: no output may replace one of its
// inputs, a file in an input folder (a sequence's images) or another of its outputs. A mistyped
// argument then costs an error message, never the data.
#include <string>
#include <vector>

namespace rgbdtam {

struct CommandFile {
  std::string option;  // how the user named it: "--out", "the ground truth"
  std::string path;    // empty: not given
  // The one output that may replace this input (replay's --map-out over its --map-in: the map
  // is read whole at init and replaced only by a complete file).
  std::string replaced_by = "";
};

// An optional argument's path as CommandFile takes it: empty when not given.
inline std::string given_path(const char* path) { return path != nullptr ? path : ""; }

// False after printing "<program>: ..." (e.g. "rgbdtam replay") on stderr when an output
// clashes.
bool outputs_are_safe(const char* command, const std::vector<CommandFile>& outputs,
                      const std::vector<CommandFile>& inputs,
                      const std::vector<std::string>& input_folders);

// A TUM sequence's inputs: its lists, and the folders of its images.
void add_sequence_inputs(const std::string& sequence, std::vector<CommandFile>* inputs,
                         std::vector<std::string>* folders);

}  // namespace rgbdtam

#pragma once
// rgbdtam map info <file>: what a saved map holds and which build wrote it, when.

namespace rgbdtam {

int map_command(int argc, char** argv);

}  // namespace rgbdtam

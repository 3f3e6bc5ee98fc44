#pragma once
// rgbdtam map info <file>: what a saved map holds and which build wrote it, when.
// rgbdtam map export <file> --grid <prefix>: its occupancy grid for planners (map_export.hpp).

namespace rgbdtam {

int map_command(int argc, char** argv);

}  // namespace rgbdtam

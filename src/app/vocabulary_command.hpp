#pragma once
// rgbdtam vocabulary train <sequence-dir>... --config <file> --out <file>: trains the
// place-recognition vocabulary on the features of recorded sequences.

namespace rgbdtam {

int vocabulary_command(int argc, char** argv);

}  // namespace rgbdtam

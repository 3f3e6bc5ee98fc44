#pragma once
// Reading the files a run is configured by: the board's file, the parameter file (its relative
// paths resolved against its own folder) and the place-recognition vocabulary it names.

#include <memory>
#include "rgbdtam/core/vocabulary.hpp"

#include "rgbdtam/runtime/board.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

// Reads board_dir/board.conf and validates it.
Status load_board(const char* board_dir, Board* out);
Status read_params_file(const char* path, Params* p);
// Loads params.loop.vocabulary when loop.enabled; true when one was. A config that names none
// runs without loop closure, with a warning; one that cannot be read is an *error.
bool load_vocabulary(const Params& params, Vocabulary* out, Status* error);
// The bytes of a file, sized from the file (init time).
Status read_binary_file(const char* path, size_t max_bytes, std::unique_ptr<uint8_t[]>* data,
                        size_t* size);

}  // namespace rgbdtam

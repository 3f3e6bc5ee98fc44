#pragma once
// Whole-file reads into caller-owned buffers, through open/read so that no stdio buffer
// is allocated.

#include <cstddef>
#include <cstdint>

#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

// Reads `path` into buf; fails with kOutOfRange when the file is larger than capacity.
Status read_file(const char* path, uint8_t* buf, size_t capacity, size_t* size);
// Init-time helper: reads a text file into a new NUL-terminated buffer of at most max_bytes.
Status read_text_file(const char* path, size_t max_bytes, char** text);

}  // namespace rgbdtam

#pragma once
// What this machine has, as the operating system reports it.

#include <cstdint>

namespace rgbdtam {

// Physical memory in bytes; 0 when the system does not say.
uint64_t physical_memory_bytes();

}  // namespace rgbdtam

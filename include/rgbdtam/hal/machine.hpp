#pragma once
// What this machine has, as the operating system reports it.

#include <cstdint>

namespace rgbdtam {

// Physical memory in bytes; 0 when the system does not say.
uint64_t physical_memory_bytes();
// What this process holds in memory now (its resident set) in bytes; 0 when unknown.
uint64_t resident_bytes();

}  // namespace rgbdtam

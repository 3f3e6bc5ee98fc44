#include "rgbdtam/hal/machine.hpp"

#include <unistd.h>

#include <cstdio>

namespace rgbdtam {

uint64_t physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page_size = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page_size <= 0) return 0;
  return static_cast<uint64_t>(pages) * static_cast<uint64_t>(page_size);
}

uint64_t resident_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  long size = 0, resident = 0;
  const int got = std::fscanf(f, "%ld %ld", &size, &resident);
  std::fclose(f);
  const long page_size = ::sysconf(_SC_PAGE_SIZE);
  if (got != 2 || resident < 0 || page_size <= 0) return 0;
  return static_cast<uint64_t>(resident) * static_cast<uint64_t>(page_size);
}

}  // namespace rgbdtam

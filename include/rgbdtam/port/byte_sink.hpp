#pragma once
// Where the map file's bytes go: a stream (ByteSink) for writing, and a whole-or-nothing file
// (MapFileTarget) for saves while running; hal's atomic file writer is one.

#include <cstddef>

#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

class ByteSink {
 public:
  virtual ~ByteSink() = default;
  virtual bool write(const void* data, size_t size) = 0;
};

// Where a save goes: a new file beside the map, then synced and renamed over it; commit()
// refuses (and names the error) when a write since begin() failed.
class MapFileTarget : public ByteSink {
 public:
  virtual Status begin() = 0;
  virtual Status commit() = 0;
};

}  // namespace rgbdtam

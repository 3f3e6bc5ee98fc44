#pragma once
// A map file written whole or not at all (MapFileTarget), through open/write with a buffer
// allocated once at init: no stdio and no allocation per save, so the loop module's thread can
// save while running. Each save goes to <path>.partial, is synced, renamed over path, and the
// folder synced: a power cut at any instant leaves the old file or the new one. A save that
// fails removes its .partial file.

#include <climits>
#include <memory>

#include "rgbdtam/port/byte_sink.hpp"

namespace rgbdtam {

class AtomicFileWriter : public MapFileTarget {
 public:
  ~AtomicFileWriter() override;
  Status init(const char* path, size_t buffer_bytes = size_t{1} << 16);
  Status begin() override;
  bool write(const void* data, size_t size) override;
  Status commit() override;

 private:
  bool flush();
  Status fail(const char* what);
  int fd_ = -1;
  char path_[PATH_MAX] = "";
  char partial_[PATH_MAX + 16] = "";
  std::unique_ptr<uint8_t[]> buffer_;
  size_t capacity_ = 0, used_ = 0;
  Status status_;
};

}  // namespace rgbdtam

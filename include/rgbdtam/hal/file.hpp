#pragma once
// Whole-file reads into caller-owned buffers, through open/read so that no stdio buffer
// is allocated.

#include <climits>
#include <cstddef>
#include <cstdint>
#include <cstdio>

#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

// After a rename into `path`: syncs its folder so the new name is on the disk. Best effort: a
// folder that cannot be opened or synced (some network file systems) leaves the rename to the
// kernel's own schedule.
void sync_folder_of(const char* path);

// Reads `path` into buf; fails with kOutOfRange when the file is larger than capacity.
Status read_file(const char* path, uint8_t* buf, size_t capacity, size_t* size);
// Init-time helper: reads a text file into a new NUL-terminated buffer of at most max_bytes.
Status read_text_file(const char* path, size_t max_bytes, char** text);

// For an output written at the end of a job, checked at its start: `path` is not a folder and
// its folder takes a new file (the probe, <path>.partial, is removed again).
Status check_can_create(const char* path);

// An output file written as `<path>.partial` and renamed to `path` when complete, so that a
// reader never finds half a file under the real name and an interrupted one is still there.
// A path that exists and is not a regular file (a device, a FIFO) is written directly. The
// first failure is kept, naming the file and the reason; after it, commit() removes the
// .partial file.
class OutputFile {
 public:
  ~OutputFile();  // unfinished: closed and left as .partial
  // buffer: the stdio buffer, owned by the caller (no allocation after open).
  Status open(const char* path, char* buffer, size_t size);
  bool is_open() const { return file_ != nullptr; }
  std::FILE* stream() { return file_; }
  // After a write through stream(): records the failure, if any, and returns the first one.
  Status check(bool write_ok);
  Status flush();
  // Flushes, closes and renames into place; the first failure, if any.
  Status commit();
  const Status& status() const { return status_; }

 private:
  Status fail(const char* what);
  std::FILE* file_ = nullptr;
  bool direct_ = false;
  char path_[PATH_MAX] = "";
  char partial_[PATH_MAX + 16] = "";
  Status status_;
};

}  // namespace rgbdtam

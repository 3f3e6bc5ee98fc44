#pragma once
// The V4L2 system calls behind a seam, so that tests script a fake device.

#include <sys/types.h>
#include <cstddef>
#include <cstdint>

namespace rgbdtam {

// A pixel format's four characters, printable ('?' where not), for messages.
void v4l2_fourcc_text(uint32_t fourcc, char out[5]);

class V4l2Io {
 public:
  virtual ~V4l2Io() = default;
  virtual int open(const char* path, int flags) = 0;
  virtual int close(int fd) = 0;
  virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
  virtual void* mmap(size_t length, int fd, off_t offset) = 0;
  virtual int munmap(void* address, size_t length) = 0;
  // > 0 readable, 0 timed out, < 0 error (errno set).
  virtual int poll(int fd, int timeout_ms) = 0;
};

// The real system calls.
class SystemV4l2Io : public V4l2Io {
 public:
  int open(const char* path, int flags) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(size_t length, int fd, off_t offset) override;
  int munmap(void* address, size_t length) override;
  int poll(int fd, int timeout_ms) override;
};

}  // namespace rgbdtam

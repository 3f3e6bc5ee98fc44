#include "rgbdtam/hal/file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace rgbdtam {

Status read_file(const char* path, uint8_t* buf, size_t capacity, size_t* size) {
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    return Status::error(errno == ENOENT ? StatusCode::kNotFound : StatusCode::kIoError, "%s: %s",
                         path, std::strerror(errno));
  }
  size_t total = 0;
  for (;;) {
    if (total == capacity) {
      uint8_t probe;
      const ssize_t extra = ::read(fd, &probe, 1);
      ::close(fd);
      if (extra > 0) {
        return Status::error(StatusCode::kOutOfRange, "%s: larger than the %zu-byte buffer", path,
                             capacity);
      }
      break;
    }
    const ssize_t n = ::read(fd, buf + total, capacity - total);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      return Status::error(StatusCode::kIoError, "%s: %s", path, std::strerror(err));
    }
    if (n == 0) {
      ::close(fd);
      break;
    }
    total += static_cast<size_t>(n);
  }
  *size = total;
  return Status::ok();
}

Status read_text_file(const char* path, size_t max_bytes, char** text) {
  struct stat st;
  if (::stat(path, &st) != 0) {
    return Status::error(StatusCode::kNotFound, "%s: %s", path, std::strerror(errno));
  }
  if (static_cast<size_t>(st.st_size) > max_bytes) {
    return Status::error(StatusCode::kOutOfRange, "%s: larger than %zu bytes", path, max_bytes);
  }
  const size_t capacity = static_cast<size_t>(st.st_size) + 1;
  char* buf = new char[capacity];
  size_t size = 0;
  const Status s = read_file(path, reinterpret_cast<uint8_t*>(buf), capacity - 1, &size);
  if (!s.is_ok()) {
    delete[] buf;
    return s;
  }
  buf[size] = '\0';
  if (std::strlen(buf) != size) {
    delete[] buf;
    return Status::error(StatusCode::kCorrupt, "%s: contains a NUL byte; not a text file", path);
  }
  *text = buf;
  return Status::ok();
}

}  // namespace rgbdtam

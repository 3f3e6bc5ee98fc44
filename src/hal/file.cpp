#include "rgbdtam/hal/file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace rgbdtam {

Status read_file(const char* path, uint8_t* buf, size_t capacity, size_t* size) {
  // Non-blocking, so that a FIFO (or a device) is refused instead of waiting for a writer.
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    return Status::error(errno == ENOENT ? StatusCode::kNotFound : StatusCode::kIoError, "%s: %s",
                         path, std::strerror(errno));
  }
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Status::error(StatusCode::kIoError, "%s: not a regular file", path);
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

OutputFile::~OutputFile() {
  if (file_ != nullptr) std::fclose(file_);
}

void sync_folder_of(const char* path) {
  char folder[PATH_MAX];
  std::snprintf(folder, sizeof(folder), "%s", path);
  char* slash = std::strrchr(folder, '/');
  if (slash == nullptr) {
    std::snprintf(folder, sizeof(folder), ".");
  } else if (slash == folder) {
    slash[1] = '\0';
  } else {
    *slash = '\0';
  }
  const int fd = ::open(folder, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

Status OutputFile::open(const char* path, char* buffer, size_t size) {
  if (std::snprintf(path_, sizeof(path_), "%s", path) >= static_cast<int>(sizeof(path_))) {
    return Status::error(StatusCode::kInvalidArgument, "%s: path too long", path);
  }
  struct stat st;
  direct_ = ::stat(path, &st) == 0 && !S_ISREG(st.st_mode);
  std::snprintf(partial_, sizeof(partial_), direct_ ? "%s" : "%s.partial", path);
  file_ = std::fopen(partial_, "wb");
  if (file_ == nullptr) return fail("cannot create");
  std::setvbuf(file_, buffer, _IOFBF, size);
  status_ = Status::ok();
  return status_;
}

Status OutputFile::fail(const char* what) {
  if (status_.is_ok()) {
    status_ = Status::error(StatusCode::kIoError, "%s: %s: %s", partial_, what,
                            std::strerror(errno != 0 ? errno : EIO));
  }
  return status_;
}

Status OutputFile::check(bool write_ok) { return write_ok ? status_ : fail("write failed"); }

Status OutputFile::flush() {
  if (file_ != nullptr && status_.is_ok() && std::fflush(file_) != 0) return fail("write failed");
  return status_;
}

Status OutputFile::commit() {
  if (file_ == nullptr) return status_;
  (void)flush();
  // On the disk before it takes the real name, and the name on the disk after: a power cut
  // leaves the old file or the new one, whole.
  if (status_.is_ok() && !direct_ && ::fsync(fileno(file_)) != 0) (void)fail("sync failed");
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!closed) (void)fail("close failed");
  if (status_.is_ok() && !direct_ && std::rename(partial_, path_) != 0) {
    (void)fail("cannot rename into place");
  }
  if (!direct_) {
    if (status_.is_ok()) {
      sync_folder_of(path_);
    } else {
      (void)::unlink(partial_);  // a failed write leaves nothing behind
    }
  }
  return status_;
}

Status check_can_create(const char* path) {
  struct stat st;
  if (::stat(path, &st) == 0) {
    if (S_ISDIR(st.st_mode)) {
      return Status::error(StatusCode::kInvalidArgument, "%s: is a folder, not a file", path);
    }
    if (!S_ISREG(st.st_mode)) return Status::ok();  // a device or FIFO, written directly
  }
  char partial[PATH_MAX + 16];
  std::snprintf(partial, sizeof(partial), "%s.partial", path);
  const bool was_there = ::stat(partial, &st) == 0;
  const int fd = ::open(partial, O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    return Status::error(StatusCode::kIoError, "%s: cannot create: %s", partial,
                         std::strerror(errno));
  }
  ::close(fd);
  if (!was_there) (void)::unlink(partial);
  return Status::ok();
}

}  // namespace rgbdtam

#include "rgbdtam/hal/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "rgbdtam/hal/file.hpp"

namespace rgbdtam {

AtomicFileWriter::~AtomicFileWriter() {
  if (fd_ >= 0) ::close(fd_);
}

Status AtomicFileWriter::init(const char* path, size_t buffer_bytes) {
  if (std::snprintf(path_, sizeof(path_), "%s", path) >= static_cast<int>(sizeof(path_))) {
    return Status::error(StatusCode::kInvalidArgument, "%s: path too long", path);
  }
  std::snprintf(partial_, sizeof(partial_), "%s.partial", path);
  buffer_.reset(new uint8_t[buffer_bytes]);
  capacity_ = buffer_bytes;
  return Status::ok();
}

Status AtomicFileWriter::fail(const char* what) {
  if (status_.is_ok()) {
    status_ = Status::error(StatusCode::kIoError, "%s: %s: %s", partial_, what,
                            std::strerror(errno != 0 ? errno : EIO));
  }
  return status_;
}

Status AtomicFileWriter::begin() {
  if (fd_ >= 0) ::close(fd_);
  status_ = Status::ok();
  used_ = 0;
  fd_ = ::open(partial_, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) return fail("cannot create");
  return status_;
}

bool AtomicFileWriter::flush() {
  for (size_t done = 0; done < used_;) {
    const ssize_t n = ::write(fd_, buffer_.get() + done, used_ - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      (void)fail("write failed");
      return false;
    }
    done += static_cast<size_t>(n);
  }
  used_ = 0;
  return true;
}

bool AtomicFileWriter::write(const void* data, size_t size) {
  if (fd_ < 0 || !status_.is_ok()) return false;
  const uint8_t* bytes = static_cast<const uint8_t*>(data);
  while (size > 0) {
    if (used_ == capacity_ && !flush()) return false;
    const size_t n = size < capacity_ - used_ ? size : capacity_ - used_;
    std::memcpy(buffer_.get() + used_, bytes, n);
    used_ += n;
    bytes += n;
    size -= n;
  }
  return true;
}

Status AtomicFileWriter::commit() {
  if (fd_ < 0) return status_.is_ok() ? fail("not begun") : status_;
  // On the disk before it takes the real name, and the name on the disk after.
  if (status_.is_ok() && flush() && ::fsync(fd_) != 0) (void)fail("sync failed");
  if (::close(fd_) != 0) (void)fail("close failed");
  fd_ = -1;
  if (status_.is_ok() && std::rename(partial_, path_) != 0) (void)fail("cannot rename into place");
  if (status_.is_ok()) {
    sync_folder_of(path_);
  } else {
    (void)::unlink(partial_);  // half a map is of no use, and may fill what the disk has left
  }
  return status_;
}

}  // namespace rgbdtam

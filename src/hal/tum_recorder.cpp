#include "rgbdtam/hal/tum_recorder.hpp"

#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>

#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/tum_timestamp.hpp"

namespace rgbdtam {
namespace {
Status make_dir(const char* path) {
  if (::mkdir(path, 0755) == 0 || errno == EEXIST) return Status::ok();
  return Status::error(StatusCode::kIoError, "%s: %s", path, std::strerror(errno));
}

bool write_all(int fd, const void* data, size_t n) {
  const auto* p = static_cast<const uint8_t*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

Status open_list(const char* dir, const char* name, const char* header, int* fd) {
  char path[512];
  std::snprintf(path, sizeof(path), "%s/%s", dir, name);
  *fd = ::open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (*fd < 0) {
    return Status::error(StatusCode::kIoError, "%s: %s%s", path, std::strerror(errno),
                         errno == EEXIST ? " (the folder holds a recording already)" : "");
  }
  if (!write_all(*fd, header, std::strlen(header))) {
    return Status::error(StatusCode::kIoError, "%s: %s", path, std::strerror(errno));
  }
  return Status::ok();
}
}  // namespace

TumRecorder::~TumRecorder() { (void)finish(); }

Status TumRecorder::open(const char* out_dir, const SensorImageSize& size) {
  if (std::snprintf(dir_, sizeof(dir_), "%s", out_dir) >= static_cast<int>(sizeof(dir_))) {
    return Status::error(StatusCode::kInvalidArgument, "output folder path too long");
  }
  size_ = size;
  char sub[450];
  RGBDTAM_RETURN_IF_ERROR(make_dir(dir_));
  std::snprintf(sub, sizeof(sub), "%s/rgb", dir_);
  RGBDTAM_RETURN_IF_ERROR(make_dir(sub));
  std::snprintf(sub, sizeof(sub), "%s/depth", dir_);
  RGBDTAM_RETURN_IF_ERROR(make_dir(sub));
  RGBDTAM_RETURN_IF_ERROR(open_list(dir_, "rgb.txt",
                                    "# colour images (8-bit grey), recorded by rgbdtam\n"
                                    "# timestamp filename\n",
                                    &rgb_list_));
  RGBDTAM_RETURN_IF_ERROR(open_list(dir_, "depth.txt",
                                    "# depth images (16-bit), recorded by rgbdtam\n"
                                    "# timestamp filename\n",
                                    &depth_list_));
  queue_.allocate(kQueueSlots);
  for (int i = 0; i < kQueueSlots; ++i) {
    queue_.slot(i).gray.allocate(size.width_px, size.height_px);
    queue_.slot(i).depth.allocate(size.depth_width_px, size.depth_height_px);
  }
  encoder_.allocate(std::max(size.width_px, size.depth_width_px),
                    std::max(size.height_px, size.depth_height_px));
  return Status::ok();
}

Status TumRecorder::start(const ThreadPlacement& placement) {
  return worker_.start(&queue_, &writer_, placement, "rgbdtam-record",
                       std::chrono::milliseconds(20));
}

bool TumRecorder::push(const SensorFrame& frame) {
  Slot* s = queue_.begin_push();
  if (s == nullptr || frame.width_px != size_.width_px || frame.height_px != size_.height_px ||
      frame.depth_width_px != size_.depth_width_px ||
      frame.depth_height_px != size_.depth_height_px) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  std::memcpy(s->gray.data(), frame.gray, size_.pixels());
  s->has_depth = frame.depth != nullptr;
  if (s->has_depth) {
    std::memcpy(s->depth.data(), frame.depth, size_.depth_pixels() * sizeof(uint16_t));
  }
  s->timestamp_ns = frame.timestamp_ns;
  s->depth_timestamp_ns = frame.depth_timestamp_ns;
  queue_.publish();
  worker_.notify();
  return true;
}

Status TumRecorder::write_file(const char* relative, const uint8_t* bytes, size_t n) {
  char path[512];
  std::snprintf(path, sizeof(path), "%s/%s", dir_, relative);
  const int fd = ::open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Status::error(StatusCode::kIoError, "%s: %s", path, std::strerror(errno));
  const bool ok = write_all(fd, bytes, n);
  const int err = errno;
  if (::close(fd) != 0 || !ok) {
    const Status failed =
        Status::error(StatusCode::kIoError, "%s: %s", path, std::strerror(ok ? errno : err));
    ::unlink(path);  // no half image left behind (nor listed)
    return failed;
  }
  bytes_.fetch_add(n, std::memory_order_relaxed);
  return Status::ok();
}

Status TumRecorder::store_encoded(const char* folder, int64_t stamp_ns, int list_fd) {
  char stamp[32], relative[64], line[128];
  format_seconds(stamp_ns, stamp, sizeof(stamp));
  std::snprintf(relative, sizeof(relative), "%s/%s.png", folder, stamp);
  RGBDTAM_RETURN_IF_ERROR(write_file(relative, encoder_.data(), encoder_.size()));
  const int n = std::snprintf(line, sizeof(line), "%s %s\n", stamp, relative);
  if (!write_all(list_fd, line, static_cast<size_t>(n))) {
    return Status::error(StatusCode::kIoError, "%s: list write failed: %s", dir_,
                         std::strerror(errno));
  }
  return Status::ok();
}

Status TumRecorder::write_frame(const Slot& s) {
  RGBDTAM_RETURN_IF_ERROR(encoder_.encode_gray8(s.gray.data(), size_.width_px, size_.height_px));
  RGBDTAM_RETURN_IF_ERROR(store_encoded("rgb", s.timestamp_ns, rgb_list_));
  written_.fetch_add(1, std::memory_order_relaxed);
  if (!s.has_depth || s.depth_timestamp_ns == last_depth_ns_) return Status::ok();
  last_depth_ns_ = s.depth_timestamp_ns;
  RGBDTAM_RETURN_IF_ERROR(
      encoder_.encode_gray16(s.depth.data(), size_.depth_width_px, size_.depth_height_px));
  RGBDTAM_RETURN_IF_ERROR(store_encoded("depth", s.depth_timestamp_ns, depth_list_));
  depth_written_.fetch_add(1, std::memory_order_relaxed);
  return Status::ok();
}

void TumRecorder::keep_first_error(const Status& s) {
  if (s.is_ok() || failed()) return;
  error_ = s;
  failed_.store(true, std::memory_order_release);
}

void TumRecorder::Writer::step(const Slot& s) {
  const int64_t t0 = monotonic_ns();
  recorder->keep_first_error(recorder->failed() ? Status::ok() : recorder->write_frame(s));
  recorder->per_frame_.add(monotonic_ns() - t0);
}

Status TumRecorder::finish() {
  if (worker_.running()) worker_.stop();  // writes what is queued first
  for (int* fd : {&rgb_list_, &depth_list_}) {
    if (*fd >= 0 && ::close(*fd) != 0 && error_.is_ok()) {
      error_ =
          Status::error(StatusCode::kIoError, "%s: closing a list: %s", dir_, std::strerror(errno));
    }
    *fd = -1;
  }
  return error_;
}

RecorderCounters TumRecorder::counters() const {
  RecorderCounters c;
  c.written = written_.load();
  c.depth_written = depth_written_.load();
  c.dropped = dropped_.load();
  c.bytes = bytes_.load();
  return c;
}

}  // namespace rgbdtam

#pragma once
// UVC RGB-D cameras through V4L2: a 16-bit depth node (Z16) and a colour node (YUYV, or MJPEG
// decoded by JpegDecoder into a buffer sized at open), driven
// with raw ioctls and mmap buffers. Frames are paired by their buffer timestamps (same clock on
// both nodes) and copied out, so a SensorFrame stays valid until the next one; nothing is
// allocated per frame. The system calls go through V4l2Io, so tests script a fake device.

#include <sys/types.h>
#include <cstddef>
#include <cstdint>

#include "rgbdtam/core/image.hpp"
#include "rgbdtam/hal/jpeg_decoder.hpp"
#include "rgbdtam/port/sensor_source.hpp"

namespace rgbdtam {

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

struct V4l2Counters {
  uint32_t delivered = 0;
  uint32_t error_buffers = 0;  // dequeued with V4L2_BUF_FLAG_ERROR: skipped and requeued
  uint32_t unpaired = 0;       // frames without a partner within the pairing limit
  uint32_t retries = 0;        // EINTR / EAGAIN
  uint32_t overtaken = 0;      // older filled buffers let go for a newer one (newest kept)
};

// One capture node: format negotiation, mmap buffers, streaming.
class V4l2Stream {
 public:
  static constexpr int kBuffers = 4;
  ~V4l2Stream();
  Status open(V4l2Io* io, const char* path, uint32_t fourcc, int width, int height);
  // The newest filled buffer (waits up to timeout_ms for one; older ones already waiting are
  // requeued and counted as overtaken). Must be released before the next take.
  Status take(int timeout_ms, int* index, int64_t* timestamp_ns, V4l2Counters* counters);
  Status release(int index);
  const uint8_t* data(int index) const {
    return static_cast<const uint8_t*>(buffers_[index].start);
  }
  size_t bytes_used(int index) const { return buffers_[index].used; }
  void close();

 private:
  struct Buffer {
    void* start = nullptr;
    size_t length = 0;
    size_t used = 0;
  };
  V4l2Io* io_ = nullptr;
  int fd_ = -1;
  char path_[128] = {};
  Buffer buffers_[kBuffers];
  int count_ = 0;
  bool streaming_ = false;
};

enum class V4l2Colour { kYuyv, kMjpeg };

class V4l2Source : public LiveSensor {
 public:
  // depth_path: the Z16 node; colour_path: the colour node (YUYV or MJPEG); frames width x
  // height on both.
  Status open(V4l2Io* io, const char* depth_path, const char* colour_path, int width, int height,
              int64_t max_pair_dt_ns, int timeout_ms, V4l2Colour colour = V4l2Colour::kYuyv);
  Status next(SensorFrame* frame, Status* warning) override;
  // The streams run from open(); start() and stop() have nothing more to do.
  Status start(const ThreadPlacement&) override { return Status::ok(); }
  void stop() override {}
  int64_t arrival_ns() const override { return arrival_ns_; }
  uint32_t dropped() const override { return counters_.overtaken; }
  const V4l2Counters& counters() const { return counters_; }
  const JpegDecoder& jpeg() const { return jpeg_; }
  void close();

 private:
  Status open_stream() override;
  void close_stream() override { close(); }

  V4l2Io* io_ = nullptr;
  char depth_path_[128] = {}, colour_path_[128] = {};
  V4l2Stream depth_, colour_;
  V4l2Colour colour_format_ = V4l2Colour::kYuyv;
  JpegDecoder jpeg_;
  ImageU8 gray_;
  ImageU16 depth_img_;
  int width_ = 0, height_ = 0;
  int64_t max_pair_dt_ns_ = 0;
  int timeout_ms_ = 0;
  uint32_t sequence_ = 0;
  int64_t arrival_ns_ = 0;
  V4l2Counters counters_;
};

}  // namespace rgbdtam

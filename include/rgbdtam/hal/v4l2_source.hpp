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
#include "rgbdtam/hal/usb_devices.hpp"
#include "rgbdtam/hal/v4l2_io.hpp"
#include "rgbdtam/hal/v4l2_nodes.hpp"
#include "rgbdtam/port/sensor_source.hpp"

namespace rgbdtam {

struct V4l2Counters {
  uint32_t delivered = 0;
  uint32_t error_buffers = 0;     // dequeued with V4L2_BUF_FLAG_ERROR: skipped and requeued
  uint32_t unpaired = 0;          // frames without a partner within the pairing limit
  uint32_t retries = 0;           // EINTR / EAGAIN
  uint32_t overtaken = 0;         // older filled buffers let go for a newer one (newest kept)
  uint32_t requeue_failures = 0;  // VIDIOC_QBUF refused: the buffer is queued again later
  // Depth stamp minus colour stamp over the delivered pairs: how far apart the two nodes'
  // frames are (the sum, for the mean, and the extremes).
  int64_t pair_offset_sum_ns = 0;
  int64_t pair_offset_min_ns = 0;
  int64_t pair_offset_max_ns = 0;
  double mean_pair_offset_ns() const {
    return delivered > 0 ? static_cast<double>(pair_offset_sum_ns) / delivered : 0.0;
  }
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
  // Gives the buffer back to the driver. A refusal other than an unplug (D4xx cameras on a
  // Raspberry Pi 4 refuse now and then) is counted and the buffer queued again at the next
  // take(), as librealsense does; a stream that keeps refusing runs dry and stalls, which
  // SensorRecovery resets and reopens.
  Status release(int index, V4l2Counters* counters);
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
  Status queue(int index);
  Status requeue_owed(V4l2Counters* counters);
  Buffer buffers_[kBuffers];
  bool owed_[kBuffers] = {};  // refused by VIDIOC_QBUF, not yet queued again
  int count_ = 0;
  bool streaming_ = false;
};

enum class V4l2Colour { kYuyv, kMjpeg };

class V4l2Source : public LiveSensor {
 public:
  // depth_path: the Z16 node; colour_path: the colour node (YUYV or MJPEG), both empty when
  // locate_by_usb() was called first; frames width x height on both.
  Status open(V4l2Io* io, const char* depth_path, const char* colour_path, int width, int height,
              int64_t max_pair_dt_ns, int timeout_ms, V4l2Colour colour = V4l2Colour::kYuyv);
  // Init time, before open(): the nodes are found by the camera's USB id and what they offer
  // (V4l2NodeFinder), at every open, since a USB reset may renumber them.
  void locate_by_usb(const UsbId& usb, const char* sysfs_root, const char* devfs_root);
  const V4l2Nodes& nodes() const { return nodes_; }
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
  bool by_usb_ = false;
  UsbId usb_;
  const char* sysfs_root_ = "/sys";
  const char* devfs_root_ = "/dev";
  V4l2NodeFinder finder_;
  V4l2Nodes nodes_;
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

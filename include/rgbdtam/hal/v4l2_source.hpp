#pragma once
// UVC RGB-D cameras through V4L2: a 16-bit depth node (Z16) and a colour node (YUYV, or MJPEG
// decoded by JpegDecoder into a buffer sized at open), driven
// with raw ioctls and mmap buffers. Frames are paired by their buffer timestamps (same clock on
// both nodes), or, where uvcvideo's metadata nodes give the camera's capture stamps and its
// clock rate is known, by those (DeviceClock), and copied out, so a SensorFrame stays valid
// until the next one; nothing is allocated per frame. The system calls go through V4l2Io, so
// tests script a fake device.

#include <sys/types.h>
#include <cstddef>
#include <cstdint>

#include "rgbdtam/core/device_clock.hpp"
#include "rgbdtam/core/image.hpp"
#include "rgbdtam/hal/jpeg_decoder.hpp"
#include "rgbdtam/hal/usb_devices.hpp"
#include "rgbdtam/hal/uvc_metadata.hpp"
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
  uint32_t camera_stamped = 0;    // pairs stamped and paired on the camera's clock
  uint32_t metadata_missing = 0;  // frames whose metadata did not come (stamped on arrival)
  // Metadata buffers flagged as errors (uvcvideo flags them with their frame's): counted here,
  // not in error_buffers, so that one bad frame counts once there.
  uint32_t metadata_errors = 0;
  // Frames the camera counted (its frame counter) that never reached the driver: lost in the
  // camera or on the USB, not overtaken here.
  uint32_t lost_before_driver = 0;
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
  // A uvcvideo metadata node, in the D4XX format where the camera has it, else UVCH.
  Status open_metadata(V4l2Io* io, const char* path);
  // The newest filled buffer (waits up to timeout_ms for one; older ones already waiting are
  // requeued and counted as overtaken). Must be released before the next take.
  Status take(int timeout_ms, int* index, int64_t* timestamp_ns, V4l2Counters* counters);
  // Gives the buffer back to the driver. A refusal other than an unplug (D4xx cameras on a
  // Raspberry Pi 4 refuse now and then) is counted and the buffer queued again at the next
  // take(), as librealsense does; a stream that keeps refusing runs dry and stalls, which
  // SensorRecovery resets and reopens.
  Status release(int index, V4l2Counters* counters);
  // The oldest filled buffer, or index -1 when none is waiting; never waits.
  Status take_oldest(int* index, V4l2Counters* counters);
  uint32_t sequence(int index) const { return buffers_[index].sequence; }
  bool is_open() const { return fd_ >= 0; }
  const uint8_t* data(int index) const {
    return static_cast<const uint8_t*>(buffers_[index].start);
  }
  size_t bytes_used(int index) const { return buffers_[index].used; }
  // Row y of a filled buffer: a driver may pad rows (bytesperline beyond the pixels' bytes).
  const uint8_t* row(int index, int y) const {
    return data(index) + static_cast<size_t>(y) * bytes_per_line_;
  }
  // Whether the buffer holds `rows` rows of `row_bytes` each.
  bool holds(int index, int rows, size_t row_bytes) const {
    return rows > 0 &&
           bytes_used(index) >= static_cast<size_t>(rows - 1) * bytes_per_line_ + row_bytes;
  }
  void close();

 private:
  struct Buffer {
    void* start = nullptr;
    size_t length = 0;
    size_t used = 0;
    uint32_t sequence = 0;  // the driver's frame number
  };
  Status open_as(uint32_t type, V4l2Io* io, const char* path, uint32_t fourcc, int width,
                 int height);
  // One VIDIOC_DQBUF: a filled buffer's index, -1 after an error buffer (given back), or retry
  // set on EINTR/EAGAIN (errno says which).
  Status dequeue(int* index, int64_t* timestamp_ns, bool* retry, V4l2Counters* counters);
  V4l2Io* io_ = nullptr;
  uint32_t type_ = 0;  // V4L2_BUF_TYPE_VIDEO_CAPTURE or V4L2_BUF_TYPE_META_CAPTURE
  int fd_ = -1;
  size_t bytes_per_line_ = 0;  // of a video node's buffers
  char path_[128] = {};
  Status queue(int index);
  Status requeue_owed(V4l2Counters* counters);
  Buffer buffers_[kBuffers];
  bool owed_[kBuffers] = {};  // refused by VIDIOC_QBUF, not yet queued again
  int count_ = 0;
  bool streaming_ = false;
};

// A metadata node read beside its video node: each frame's metadata, found by the video
// buffer's sequence number (uvcvideo gives both buffers of a frame the same one).
class V4l2MetadataReader {
 public:
  Status open(V4l2Io* io, const char* path) { return stream_.open_metadata(io, path); }
  // Reads what waits, then looks for the frame's metadata.
  bool find(uint32_t sequence, V4l2Counters* counters, UvcFrameMetadata* out);
  bool is_open() const { return stream_.is_open(); }
  void close();

 private:
  static constexpr int kKept = 8;  // frames' metadata kept for their video buffers
  struct Kept {
    bool valid = false;
    uint32_t sequence = 0;
    UvcFrameMetadata metadata;
  };
  V4l2Stream stream_;
  Kept kept_[kKept];
  int next_ = 0;
};

enum class V4l2Colour { kYuyv, kMjpeg };

class V4l2Source : public LiveSensor {
 public:
  // depth_path: the Z16 node; colour_path: the colour node (YUYV or MJPEG), both empty when
  // locate_by_usb() was called first; each node streams at its image's size (a D4xx's depth
  // camera has its own, such as 848x480 beside colour's 640x480).
  Status open(V4l2Io* io, const char* depth_path, const char* colour_path,
              const SensorImageSize& size, int64_t max_pair_dt_ns, int timeout_ms,
              V4l2Colour colour = V4l2Colour::kYuyv);
  // Init time, before open(): the nodes are found by the camera's USB id and what they offer
  // (V4l2NodeFinder), at every open, since a USB reset may renumber them.
  void locate_by_usb(const UsbId& usb, const char* sysfs_root, const char* devfs_root);
  // Init time, before open(): the camera's clock rate in its metadata (a RealSense D4xx counts
  // microseconds). With it, and the metadata nodes found by locate_by_usb(), frames are stamped
  // and paired on the camera's clock, and the camera's frame counter counts frames lost before
  // the driver.
  void use_camera_clock(double ticks_per_s) { camera_clock_hz_ = ticks_per_s; }
  bool reads_metadata() const { return depth_meta_.is_open() && colour_meta_.is_open(); }
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
  // A stream's frame stamp: on the camera's clock when its metadata came, else its arrival.
  struct Stamped {
    bool on_camera_clock = false;
    int64_t stamp_ns = 0;
  };
  // A stream's last frame as the camera counted it and as the driver numbered it.
  struct FrameCount {
    bool seen = false;
    uint32_t camera = 0, driver = 0;
  };
  Stamped stamp(V4l2Stream* stream, V4l2MetadataReader* reader, int index, int64_t arrival_ns,
                FrameCount* count);

  V4l2Io* io_ = nullptr;
  bool by_usb_ = false;
  UsbId usb_;
  const char* sysfs_root_ = "/sys";
  const char* devfs_root_ = "/dev";
  V4l2NodeFinder finder_;
  V4l2Nodes nodes_;
  V4l2Stream depth_, colour_;
  V4l2MetadataReader depth_meta_, colour_meta_;
  double camera_clock_hz_ = 0.0;
  DeviceClock camera_clock_;  // one clock: depth and colour come from one camera
  FrameCount depth_count_, colour_count_;
  V4l2Colour colour_format_ = V4l2Colour::kYuyv;
  JpegDecoder jpeg_;
  ImageU8 gray_;
  ImageU16 depth_img_;
  SensorImageSize size_;
  int64_t max_pair_dt_ns_ = 0;
  int timeout_ms_ = 0;
  uint32_t sequence_ = 0;
  int64_t arrival_ns_ = 0;
  V4l2Counters counters_;
};

}  // namespace rgbdtam

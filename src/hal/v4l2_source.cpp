#include "rgbdtam/hal/v4l2_source.hpp"

#include <errno.h>
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "rgbdtam/hal/clock.hpp"

namespace rgbdtam {
namespace {
// Consecutive EINTR/EAGAIN answers before the device counts as stuck (a fake or a broken
// driver could otherwise keep the tracker spinning).
constexpr int kMaxRetries = 100;
}  // namespace

void v4l2_fourcc_text(uint32_t fourcc, char out[5]) {
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xFF);
    out[i] = c >= 32 && c < 127 ? c : '?';
  }
  out[4] = '\0';
}

int SystemV4l2Io::open(const char* path, int flags) { return ::open(path, flags); }
int SystemV4l2Io::close(int fd) { return ::close(fd); }
int SystemV4l2Io::ioctl(int fd, unsigned long request, void* arg) {
  return ::ioctl(fd, request, arg);
}
void* SystemV4l2Io::mmap(size_t length, int fd, off_t offset) {
  return ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset);
}
int SystemV4l2Io::munmap(void* address, size_t length) { return ::munmap(address, length); }
int SystemV4l2Io::poll(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms);
}

V4l2Stream::~V4l2Stream() { close(); }

Status V4l2Stream::open(V4l2Io* io, const char* path, uint32_t fourcc, int width, int height) {
  return open_as(V4L2_BUF_TYPE_VIDEO_CAPTURE, io, path, fourcc, width, height);
}

Status V4l2Stream::open_metadata(V4l2Io* io, const char* path) {
  return open_as(V4L2_BUF_TYPE_META_CAPTURE, io, path, V4L2_META_FMT_D4XX, 0, 0);
}

Status V4l2Stream::open_as(uint32_t type, V4l2Io* io, const char* path, uint32_t fourcc, int width,
                           int height) {
  io_ = io;
  type_ = type;
  const bool metadata = type == V4L2_BUF_TYPE_META_CAPTURE;
  std::snprintf(path_, sizeof(path_), "%s", path);
  fd_ = io->open(path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    return Status::error(StatusCode::kNotFound, "%s: %s", path, std::strerror(errno));
  }
  v4l2_capability cap{};
  if (io->ioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) {
    return Status::error(StatusCode::kIoError, "%s: not a V4L2 device (%s)", path,
                         std::strerror(errno));
  }
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  const uint32_t capture = metadata ? V4L2_CAP_META_CAPTURE : V4L2_CAP_VIDEO_CAPTURE;
  if ((caps & capture) == 0 || (caps & V4L2_CAP_STREAMING) == 0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: not a streaming %s capture node (capabilities 0x%08x)", path,
                         metadata ? "metadata" : "video", caps);
  }
  v4l2_format fmt{};
  fmt.type = type;
  char want[5], got[5];
  v4l2_fourcc_text(fourcc, want);
  if (metadata) {
    fmt.fmt.meta.dataformat = fourcc;
  } else {
    fmt.fmt.pix.width = static_cast<uint32_t>(width);
    fmt.fmt.pix.height = static_cast<uint32_t>(height);
    fmt.fmt.pix.pixelformat = fourcc;
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
  }
  if (io->ioctl(fd_, VIDIOC_S_FMT, &fmt) < 0) {
    return Status::error(StatusCode::kInvalidArgument, "%s: format %s %dx%d refused: %s", path,
                         want, width, height, std::strerror(errno));
  }
  // The driver answers with the nearest format it has: anything else is a refusal (a metadata
  // node without the camera's own format gives the standard header, which is read as well).
  if (metadata) {
    if (fmt.fmt.meta.dataformat != fourcc && fmt.fmt.meta.dataformat != V4L2_META_FMT_UVC) {
      v4l2_fourcc_text(fmt.fmt.meta.dataformat, got);
      return Status::error(StatusCode::kInvalidArgument,
                           "%s: metadata format %s refused; the node offers %s", path, want, got);
    }
  } else if (fmt.fmt.pix.pixelformat != fourcc ||
             fmt.fmt.pix.width != static_cast<uint32_t>(width) ||
             fmt.fmt.pix.height != static_cast<uint32_t>(height)) {
    v4l2_fourcc_text(fmt.fmt.pix.pixelformat, got);
    return Status::error(StatusCode::kInvalidArgument,
                         "%s: format %s %dx%d refused; the device offers %s %ux%u", path, want,
                         width, height, got, fmt.fmt.pix.width, fmt.fmt.pix.height);
  }
  if (!metadata) {
    // Packed formats' rows are width x 2 bytes, or padded beyond; 0 (compressed MJPEG): unused.
    const uint32_t packed = static_cast<uint32_t>(width) * 2;
    const uint32_t line = fmt.fmt.pix.bytesperline;
    if (fourcc != V4L2_PIX_FMT_MJPEG && line != 0 && line < packed) {
      return Status::error(StatusCode::kInvalidArgument,
                           "%s: rows of %u bytes are shorter than %d pixels of %s", path, line,
                           width, want);
    }
    bytes_per_line_ = line != 0 ? line : packed;
  }
  v4l2_requestbuffers req{};
  req.count = kBuffers;
  req.type = type;
  req.memory = V4L2_MEMORY_MMAP;
  if (io->ioctl(fd_, VIDIOC_REQBUFS, &req) < 0 || req.count < 2) {
    return Status::error(StatusCode::kIoError, "%s: no mmap buffers (%s)", path,
                         std::strerror(errno));
  }
  count_ = static_cast<int>(req.count < kBuffers ? req.count : kBuffers);
  for (int i = 0; i < count_; ++i) {
    v4l2_buffer b{};
    b.type = type;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = static_cast<uint32_t>(i);
    if (io->ioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) {
      return Status::error(StatusCode::kIoError, "%s: buffer %d: %s", path, i,
                           std::strerror(errno));
    }
    void* start = io->mmap(b.length, fd_, static_cast<off_t>(b.m.offset));
    if (start == MAP_FAILED) {
      return Status::error(StatusCode::kIoError, "%s: mapping buffer %d: %s", path, i,
                           std::strerror(errno));
    }
    buffers_[i].start = start;
    buffers_[i].length = b.length;
    owed_[i] = false;
    RGBDTAM_RETURN_IF_ERROR(queue(i));
  }
  v4l2_buf_type stream_type = static_cast<v4l2_buf_type>(type);
  if (io->ioctl(fd_, VIDIOC_STREAMON, &stream_type) < 0) {
    return Status::error(StatusCode::kIoError, "%s: stream on: %s", path, std::strerror(errno));
  }
  streaming_ = true;
  return Status::ok();
}

Status V4l2Stream::queue(int index) {
  v4l2_buffer b{};
  b.type = type_;
  b.memory = V4L2_MEMORY_MMAP;
  b.index = static_cast<uint32_t>(index);
  if (io_->ioctl(fd_, VIDIOC_QBUF, &b) < 0) {
    const int error = errno;
    return Status::error(error == ENODEV ? StatusCode::kNotFound : StatusCode::kIoError,
                         "%s: queueing buffer %d: %s", path_, index,
                         error == ENODEV ? "device unplugged" : std::strerror(error));
  }
  return Status::ok();
}

Status V4l2Stream::release(int index, V4l2Counters* counters) {
  const Status s = queue(index);
  if (s.is_ok() || s.code() == StatusCode::kNotFound) return s;
  ++counters->requeue_failures;
  owed_[index] = true;
  return Status::ok();
}

Status V4l2Stream::requeue_owed(V4l2Counters* counters) {
  for (int i = 0; i < count_; ++i) {
    if (!owed_[i]) continue;
    owed_[i] = false;
    RGBDTAM_RETURN_IF_ERROR(release(i, counters));
  }
  return Status::ok();
}

Status V4l2Stream::dequeue(int* index, int64_t* timestamp_ns, bool* retry, V4l2Counters* counters) {
  *index = -1;
  *retry = false;
  v4l2_buffer b{};
  b.type = type_;
  b.memory = V4L2_MEMORY_MMAP;
  if (io_->ioctl(fd_, VIDIOC_DQBUF, &b) < 0) {
    if (errno == EINTR || errno == EAGAIN) {
      *retry = true;
      return Status::ok();
    }
    return Status::error(StatusCode::kIoError, "%s: %s", path_,
                         errno == ENODEV ? "device unplugged" : std::strerror(errno));
  }
  if (b.index >= static_cast<uint32_t>(count_)) {
    return Status::error(StatusCode::kIoError, "%s: driver returned buffer %u of %d", path_,
                         b.index, count_);
  }
  if ((b.flags & V4L2_BUF_FLAG_ERROR) != 0) {
    ++counters->error_buffers;
    return release(static_cast<int>(b.index), counters);
  }
  buffers_[b.index].used = b.bytesused;
  buffers_[b.index].sequence = b.sequence;
  *index = static_cast<int>(b.index);
  *timestamp_ns = static_cast<int64_t>(b.timestamp.tv_sec) * 1000000000 +
                  static_cast<int64_t>(b.timestamp.tv_usec) * 1000;
  return Status::ok();
}

Status V4l2Stream::take(int timeout_ms, int* index, int64_t* timestamp_ns, V4l2Counters* counters) {
  *index = -1;
  RGBDTAM_RETURN_IF_ERROR(requeue_owed(counters));
  // An error while holding a buffer gives it back first.
  auto fail = [&](Status s) {
    if (*index >= 0) (void)release(*index, counters);
    *index = -1;
    return s;
  };
  int wait_ms = timeout_ms;
  for (int retries = 0; retries < kMaxRetries;) {
    const int ready = io_->poll(fd_, wait_ms);
    if (ready == 0) {
      if (*index >= 0) return Status::ok();  // nothing newer waiting
      return Status::error(StatusCode::kIoError, "%s: no frame for %d ms", path_, timeout_ms);
    }
    if (ready < 0 && errno != EINTR) {
      return fail(Status::error(StatusCode::kIoError, "%s: %s", path_,
                                errno == ENODEV ? "device unplugged" : std::strerror(errno)));
    }
    int got = -1;
    int64_t stamp_ns = 0;
    bool retry = ready < 0;
    if (!retry) {
      const Status s = dequeue(&got, &stamp_ns, &retry, counters);
      if (!s.is_ok()) return fail(s);
    }
    if (retry) {
      if (errno == EAGAIN && *index >= 0) return Status::ok();
      ++retries;
      ++counters->retries;
      continue;
    }
    if (got < 0) continue;  // an error buffer, given back
    if (*index >= 0) {      // a newer frame overtook the one held so far
      ++counters->overtaken;
      const Status r = release(*index, counters);
      *index = -1;
      if (!r.is_ok()) return fail(r);
    }
    *index = got;
    *timestamp_ns = stamp_ns;
    wait_ms = 0;  // anything already waiting is newer still
  }
  return fail(
      Status::error(StatusCode::kIoError, "%s: device keeps answering EINTR/EAGAIN", path_));
}

Status V4l2Stream::take_oldest(int* index, V4l2Counters* counters) {
  *index = -1;
  RGBDTAM_RETURN_IF_ERROR(requeue_owed(counters));
  for (int tries = 0; tries < count_ + 1; ++tries) {  // error buffers are skipped
    int64_t stamp_ns = 0;
    bool retry = false;
    RGBDTAM_RETURN_IF_ERROR(dequeue(index, &stamp_ns, &retry, counters));
    if (retry || *index >= 0) return Status::ok();
  }
  return Status::ok();
}

void V4l2Stream::close() {
  if (fd_ < 0) return;
  if (streaming_) {
    v4l2_buf_type type = static_cast<v4l2_buf_type>(type_);
    (void)io_->ioctl(fd_, VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  for (int i = 0; i < count_; ++i) {
    if (buffers_[i].start != nullptr) (void)io_->munmap(buffers_[i].start, buffers_[i].length);
    buffers_[i] = Buffer();
  }
  count_ = 0;
  (void)io_->close(fd_);
  fd_ = -1;
}

bool V4l2MetadataReader::find(uint32_t sequence, V4l2Counters* counters, UvcFrameMetadata* out) {
  V4l2Counters node;
  for (int index = -1;;) {
    if (!stream_.take_oldest(&index, &node).is_ok() || index < 0) break;
    Kept& k = kept_[next_];
    next_ = (next_ + 1) % kKept;
    k.sequence = stream_.sequence(index);
    k.valid = parse_uvc_metadata(stream_.data(index), stream_.bytes_used(index), &k.metadata);
    if (!stream_.release(index, &node).is_ok()) break;
  }
  counters->metadata_errors += node.error_buffers;
  counters->requeue_failures += node.requeue_failures;
  counters->retries += node.retries;
  for (const Kept& k : kept_) {
    if (k.valid && k.sequence == sequence) {
      *out = k.metadata;
      return true;
    }
  }
  return false;
}

void V4l2MetadataReader::close() {
  stream_.close();
  for (Kept& k : kept_) k = Kept();
  next_ = 0;
}

Status V4l2Source::open(V4l2Io* io, const char* depth_path, const char* colour_path,
                        const SensorImageSize& size, int64_t max_pair_dt_ns, int timeout_ms,
                        V4l2Colour colour) {
  colour_format_ = colour;
  if (colour == V4l2Colour::kMjpeg) {
    RGBDTAM_RETURN_IF_ERROR(jpeg_.open(size.width_px, size.height_px));
  }
  size_ = size;
  max_pair_dt_ns_ = max_pair_dt_ns;
  timeout_ms_ = timeout_ms;
  io_ = io;
  std::snprintf(nodes_.depth, sizeof(nodes_.depth), "%s", depth_path);
  std::snprintf(nodes_.colour, sizeof(nodes_.colour), "%s", colour_path);
  gray_.allocate(size.width_px, size.height_px);
  depth_img_.allocate(size.depth_width_px, size.depth_height_px);
  return open_stream();
}

void V4l2Source::locate_by_usb(const UsbId& usb, const char* sysfs_root, const char* devfs_root) {
  by_usb_ = true;
  usb_ = usb;
  sysfs_root_ = sysfs_root;
  devfs_root_ = devfs_root;
}

Status V4l2Source::open_stream() {
  const uint32_t colour =
      colour_format_ == V4l2Colour::kMjpeg ? V4L2_PIX_FMT_MJPEG : V4L2_PIX_FMT_YUYV;
  if (by_usb_) {
    RGBDTAM_RETURN_IF_ERROR(finder_.find(io_, sysfs_root_, devfs_root_, usb_, colour, &nodes_));
  }
  RGBDTAM_RETURN_IF_ERROR(depth_.open(io_, nodes_.depth, V4L2_PIX_FMT_Z16, size_.depth_width_px,
                                      size_.depth_height_px));
  RGBDTAM_RETURN_IF_ERROR(
      colour_.open(io_, nodes_.colour, colour, size_.width_px, size_.height_px));
  // Without both metadata nodes, frames are stamped on arrival as before.
  if (camera_clock_hz_ > 0.0 && nodes_.depth_metadata[0] != '\0' &&
      nodes_.colour_metadata[0] != '\0' &&
      (!depth_meta_.open(io_, nodes_.depth_metadata).is_ok() ||
       !colour_meta_.open(io_, nodes_.colour_metadata).is_ok())) {
    depth_meta_.close();
    colour_meta_.close();
  }
  camera_clock_.reset(camera_clock_hz_ > 0.0 ? camera_clock_hz_ : 1e6);
  depth_count_ = colour_count_ = FrameCount();
  return Status::ok();
}

V4l2Source::Stamped V4l2Source::stamp(V4l2Stream* stream, V4l2MetadataReader* reader, int index,
                                      int64_t arrival_ns, FrameCount* count) {
  Stamped out{false, arrival_ns};
  UvcFrameMetadata m;
  if (!reader->is_open()) return out;
  const uint32_t sequence = stream->sequence(index);
  if (!reader->find(sequence, &counters_, &m)) {
    ++counters_.metadata_missing;
    return out;
  }
  if (m.has_frame_counter) {
    // Frames the camera counted beyond those the driver numbered never reached the driver.
    const uint32_t camera_step = m.frame_counter - count->camera;
    const uint32_t driver_step = sequence - count->driver;
    if (count->seen && camera_step > driver_step && camera_step < 0x80000000u) {
      counters_.lost_before_driver += camera_step - driver_step;
    }
    *count = {true, m.frame_counter, sequence};
  }
  if (m.has_pts) out = {true, camera_clock_.to_host_ns(m.pts, arrival_ns)};
  return out;
}

Status V4l2Source::next(SensorFrame* frame, Status* warning) {
  *warning = Status::ok();
  int d = -1, c = -1;
  int64_t arrival_d = 0, arrival_c = 0;
  Stamped sd, sc;
  auto take = [&](V4l2Stream* stream, V4l2MetadataReader* reader, FrameCount* count, int* index,
                  int64_t* arrival_ns, Stamped* stamped) {
    const Status t = stream->take(timeout_ms_, index, arrival_ns, &counters_);
    if (t.is_ok()) *stamped = stamp(stream, reader, *index, *arrival_ns, count);
    return t;
  };
  auto take_depth = [&] { return take(&depth_, &depth_meta_, &depth_count_, &d, &arrival_d, &sd); };
  auto take_colour = [&] {
    return take(&colour_, &colour_meta_, &colour_count_, &c, &arrival_c, &sc);
  };
  // Depth minus colour: on the camera's clock when both frames have its stamps.
  const auto apart_ns = [&] {
    return sd.on_camera_clock && sc.on_camera_clock ? sd.stamp_ns - sc.stamp_ns
                                                    : arrival_d - arrival_c;
  };
  Status s = take_depth();
  if (s.is_ok()) s = take_colour();
  // Pair by timestamp: the older of a too-distant pair is let go.
  while (s.is_ok() && (apart_ns() > max_pair_dt_ns_ || -apart_ns() > max_pair_dt_ns_)) {
    ++counters_.unpaired;
    if (apart_ns() < 0) {
      s = depth_.release(d, &counters_);
      d = -1;
      if (s.is_ok()) s = take_depth();
    } else {
      s = colour_.release(c, &counters_);
      c = -1;
      if (s.is_ok()) s = take_colour();
    }
  }
  const bool mjpeg = colour_format_ == V4l2Colour::kMjpeg;
  const int w = size_.width_px, h = size_.height_px;
  const int depth_w = size_.depth_width_px, depth_h = size_.depth_height_px;
  const size_t depth_row_bytes = static_cast<size_t>(depth_w) * 2;
  if (s.is_ok() && (!depth_.holds(d, depth_h, depth_row_bytes) ||
                    (!mjpeg && !colour_.holds(c, h, static_cast<size_t>(w) * 2)))) {
    s = Status::error(StatusCode::kCorrupt, "short frame (%zu depth, %zu colour bytes)",
                      depth_.bytes_used(d), colour_.bytes_used(c));
  }
  if (s.is_ok() && mjpeg) s = jpeg_.decode(colour_.data(c), colour_.bytes_used(c), gray_.data());
  if (s.is_ok()) {
    for (int y = 0; y < depth_h; ++y)
      std::memcpy(depth_img_.row(y), depth_.row(d, y), depth_row_bytes);
    for (int y = 0; y < h && !mjpeg; ++y) {
      const uint8_t* yuyv = colour_.row(c, y);
      uint8_t* gray = gray_.row(y);
      for (int x = 0; x < w; ++x) gray[x] = yuyv[2 * x];  // Y of Y0 U Y1 V
    }
  }
  // Buffers go back to the driver whatever happened.
  if (d >= 0) {
    const Status r = depth_.release(d, &counters_);
    if (s.is_ok()) s = r;
  }
  if (c >= 0) {
    const Status r = colour_.release(c, &counters_);
    if (s.is_ok()) s = r;
  }
  RGBDTAM_RETURN_IF_ERROR(s);
  arrival_ns_ = monotonic_ns();
  frame->sequence = sequence_++;
  const bool camera_clock = sd.on_camera_clock && sc.on_camera_clock;
  if (camera_clock) ++counters_.camera_stamped;
  frame->timestamp_ns = camera_clock ? sc.stamp_ns : arrival_c;
  frame->depth_timestamp_ns = camera_clock ? sd.stamp_ns : arrival_d;
  const int64_t offset = frame->depth_timestamp_ns - frame->timestamp_ns;
  if (counters_.delivered == 0 || offset < counters_.pair_offset_min_ns) {
    counters_.pair_offset_min_ns = offset;
  }
  if (counters_.delivered == 0 || offset > counters_.pair_offset_max_ns) {
    counters_.pair_offset_max_ns = offset;
  }
  counters_.pair_offset_sum_ns += offset;
  frame->gray = gray_.data();
  frame->depth = depth_img_.data();
  frame->width_px = size_.width_px;
  frame->height_px = size_.height_px;
  frame->depth_width_px = size_.depth_width_px;
  frame->depth_height_px = size_.depth_height_px;
  ++counters_.delivered;
  return Status::ok();
}

void V4l2Source::close() {
  depth_.close();
  colour_.close();
  depth_meta_.close();
  colour_meta_.close();
}

}  // namespace rgbdtam

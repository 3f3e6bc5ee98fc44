#include "clip_camera.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <thread>

#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"

namespace rgbdtam::testing {
namespace {
constexpr const char* kDepthNode = "/dev/soak-depth";
constexpr const char* kColourNode = "/dev/soak-colour";
int fail(int e) {
  errno = e;
  return -1;
}
}  // namespace

ClipCamera::ClipCamera(std::vector<std::vector<uint8_t>> gray,
                       std::vector<std::vector<uint16_t>> depth, int width, int height, double fps,
                       std::vector<Outage> outages)
    : gray_(std::move(gray)),
      depth_(std::move(depth)),
      width_(width),
      height_(height),
      period_ns_(static_cast<int64_t>(1e9 / fps)),
      start_ns_(monotonic_ns()),
      outages_(std::move(outages)) {
  nodes_[0].fourcc = V4L2_PIX_FMT_Z16;
  nodes_[1].fourcc = V4L2_PIX_FMT_YUYV;
  for (Node& n : nodes_) {
    for (auto& b : n.buffers) b.assign(static_cast<size_t>(width) * height * 2, 0);
  }
}

bool ClipCamera::load(const std::string& dir, std::vector<std::vector<uint8_t>>* gray,
                      std::vector<std::vector<uint16_t>>* depth, std::vector<int64_t>* stamps_ns) {
  constexpr int kW = 640, kH = 480;
  TumReplaySource clip;
  if (!clip.open(dir.c_str(), same_size(kW, kH), 20'000'000, 0).is_ok()) return false;
  ImageU8 g;
  ImageU16 d;
  g.allocate(kW, kH);
  d.allocate(kW, kH);
  Status warning;
  for (SensorFrame f; clip.next_into(&g, &d, &f, &warning).code() != StatusCode::kEndOfStream;) {
    if (f.depth == nullptr) continue;
    gray->emplace_back(g.data(), g.data() + kW * kH);
    depth->emplace_back(d.data(), d.data() + kW * kH);
    if (stamps_ns != nullptr) stamps_ns->push_back(f.timestamp_ns);
  }
  return !gray->empty();
}

void ClipCamera::send_mjpeg(std::vector<std::vector<uint8_t>> jpeg) {
  jpeg_ = std::move(jpeg);
  nodes_[1].fourcc = V4L2_PIX_FMT_MJPEG;
}

bool ClipCamera::unplugged(int64_t now_ns) {
  const double t = (now_ns - start_ns_) * 1e-9;
  for (size_t i = 0; i < outages_.size(); ++i) {
    if (t >= outages_[i].at_s && t < outages_[i].at_s + outages_[i].for_s) {
      if (static_cast<int>(i) != last_outage_) {
        last_outage_ = static_cast<int>(i);
        outages_started_.fetch_add(1);
      }
      return true;
    }
  }
  return false;
}

int64_t ClipCamera::due_ns(int64_t frame) const { return start_ns_ + frame * period_ns_; }

ClipCamera::Node* ClipCamera::node(int fd) {
  return fd == 3 || fd == 4 ? &nodes_[fd - 3] : nullptr;
}

int ClipCamera::open(const char* path, int) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (unplugged(monotonic_ns())) return fail(ENOENT);
  const int fd = std::strcmp(path, kDepthNode) == 0    ? 3
                 : std::strcmp(path, kColourNode) == 0 ? 4
                                                       : -1;
  if (fd < 0) return fail(ENOENT);
  Node& n = nodes_[fd - 3];
  n.open = true;
  n.queued_count = 0;
  // A camera plugged in again streams what it sees now, not what it missed.
  n.next_frame = (monotonic_ns() - start_ns_) / period_ns_ + 1;
  return fd;
}

int ClipCamera::close(int fd) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (Node* n = node(fd)) n->open = false;
  return 0;
}

size_t ClipCamera::fill(const Node& n, int64_t frame, std::vector<uint8_t>* out) const {
  const size_t i = static_cast<size_t>(frame) % gray_.size();
  const size_t pixels = static_cast<size_t>(width_) * height_;
  if (n.fourcc == V4L2_PIX_FMT_Z16) {
    std::memcpy(out->data(), depth_[i].data(), pixels * 2);
    return pixels * 2;
  }
  if (n.fourcc == V4L2_PIX_FMT_MJPEG) {  // a compressed frame fits in a YUYV-sized buffer
    const std::vector<uint8_t>& jpeg = jpeg_[i % jpeg_.size()];
    std::memcpy(out->data(), jpeg.data(), std::min(jpeg.size(), out->size()));
    return std::min(jpeg.size(), out->size());
  }
  for (size_t p = 0; p < pixels; ++p) {
    (*out)[2 * p] = gray_[i][p];  // Y
    (*out)[2 * p + 1] = 128;      // U or V: grey
  }
  return pixels * 2;
}

int ClipCamera::ioctl(int fd, unsigned long request, void* arg) {
  const std::lock_guard<std::mutex> lock(mutex_);
  Node* n = node(fd);
  if (n == nullptr) return fail(EBADF);
  if (unplugged(monotonic_ns()) && request != VIDIOC_STREAMOFF) return fail(ENODEV);
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* cap = static_cast<v4l2_capability*>(arg);
      cap->capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
      return 0;
    }
    case VIDIOC_S_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      f->fmt.pix.pixelformat = n->fourcc;
      f->fmt.pix.width = static_cast<uint32_t>(width_);
      f->fmt.pix.height = static_cast<uint32_t>(height_);
      return 0;
    }
    case VIDIOC_REQBUFS:
      static_cast<v4l2_requestbuffers*>(arg)->count = kBuffers;
      n->queued_count = 0;
      return 0;
    case VIDIOC_QUERYBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      b->length = static_cast<uint32_t>(n->buffers[0].size());
      b->m.offset = b->index * 4096;
      return 0;
    }
    case VIDIOC_QBUF:
      if (n->queued_count == kBuffers) return fail(EINVAL);
      n->queued[n->queued_count++] = static_cast<int>(static_cast<v4l2_buffer*>(arg)->index);
      return 0;
    case VIDIOC_STREAMON:
    case VIDIOC_STREAMOFF:
      return 0;
    case VIDIOC_DQBUF: {
      const int64_t now = monotonic_ns();
      const bool due = driven_by_reader_ ? reader_holds_none(*n) : due_ns(n->next_frame) <= now;
      if (n->queued_count == 0 || !due) return fail(EAGAIN);
      // A real camera overwrites what nobody took: the newest frame that is due.
      const int64_t frame = driven_by_reader_
                                ? n->next_frame
                                : std::max(n->next_frame, (now - start_ns_) / period_ns_);
      n->next_frame = frame + 1;
      auto* b = static_cast<v4l2_buffer*>(arg);
      b->index = static_cast<uint32_t>(n->queued[0]);
      std::memmove(n->queued, n->queued + 1, sizeof(int) * static_cast<size_t>(--n->queued_count));
      b->bytesused = static_cast<uint32_t>(fill(*n, frame, &n->buffers[b->index]));
      b->flags = 0;
      const int64_t stamp = due_ns(frame);
      b->timestamp.tv_sec = stamp / 1000000000;
      b->timestamp.tv_usec = (stamp % 1000000000) / 1000;
      if (n->fourcc != V4L2_PIX_FMT_Z16) played_.fetch_add(1);
      return 0;
    }
    default:
      return fail(EINVAL);
  }
}

void* ClipCamera::mmap(size_t, int fd, off_t offset) {
  const std::lock_guard<std::mutex> lock(mutex_);
  Node* n = node(fd);
  if (n == nullptr || offset / 4096 >= kBuffers) return MAP_FAILED;
  return n->buffers[offset / 4096].data();
}

int ClipCamera::munmap(void*, size_t) { return 0; }

int ClipCamera::poll(int fd, int timeout_ms) {
  int64_t due = 0;
  const int64_t now = monotonic_ns();
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    Node* n = node(fd);
    if (n == nullptr) return fail(EBADF);
    if (unplugged(now)) return fail(ENODEV);
    if (driven_by_reader_) return reader_holds_none(*n) ? 1 : 0;
    due = due_ns(n->next_frame);
  }
  if (due <= now) return 1;
  const int64_t until = std::min<int64_t>(due, now + int64_t{timeout_ms} * 1'000'000);
  std::this_thread::sleep_for(std::chrono::nanoseconds(until - now));
  return until == due ? 1 : 0;
}

}  // namespace rgbdtam::testing

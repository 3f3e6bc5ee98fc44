#pragma once
// A scripted fake V4L2 device behind the V4l2Io seam, on simulated time: each node plays a
// script of frames and failures (EINTR, EAGAIN, error-flag buffers, unplug), can be wedged
// (delivers nothing until reopened), and answers format negotiation with what it offers.
// Nothing here allocates while streaming, so the allocation test can drive it too.
#include <errno.h>
#include <linux/videodev2.h>
#include <sys/mman.h>

#include <algorithm>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

#include "measures.hpp"
#include "rgbdtam/core/byte_io.hpp"
#include "rgbdtam/hal/v4l2_source.hpp"

namespace rgbdtam::testing {

// Queued buffer indices, fixed capacity (a std::deque would allocate as it cycles).
struct BufferQueue {
  int items[8] = {};
  size_t head = 0, count = 0;
  void push_back(int i) { items[(head + count++) % 8] = i; }
  int front() const { return items[head]; }
  void pop_front() {
    head = (head + 1) % 8;
    --count;
  }
  bool empty() const { return count == 0; }
  size_t size() const { return count; }
  void clear() { head = count = 0; }
};

inline constexpr int kW = 16, kH = 8;

struct Event {
  enum Kind { kFrame, kEintr, kEagain, kErrorFlag, kUnplug } kind = kFrame;
  int64_t t_ns = 0;
  uint8_t fill = 0;
  int32_t sequence = -1;  // the buffer's frame number (-1: the node's count of frames so far)
  // Metadata nodes: the camera's clock at capture and its frame counter (D4XX format only).
  uint32_t pts = 0;
  uint32_t frame_counter = 0;
};

class FakeV4l2 : public V4l2Io {
 public:
  struct Node {
    std::string path;
    uint32_t fourcc;  // what the device offers
    std::deque<Event> script;
    std::vector<std::vector<uint8_t>> buffers;
    BufferQueue queued;  // buffers the driver may fill, in order
    bool open = false;
    bool wedged = false;  // delivers nothing until opened again
    int opens = 0;
    std::vector<std::vector<uint8_t>> jpeg;    // MJPEG: a frame's fill picks one of these
    std::vector<uint32_t> also_offers;         // VIDIOC_ENUM_FMT: fourcc first, then these
    bool metadata = false;                     // a UVC metadata node (no video capture)
    int qbuf_failures = 0;                     // the next VIDIOC_QBUFs fail with EIO
    bool qbuf_broken = false;                  // every VIDIOC_QBUF fails until opened again
    uint32_t meta_format = V4L2_META_FMT_UVC;  // a metadata node's format (UVCH or D4XX)
    uint32_t frames = 0;                       // frames delivered (their sequence numbers)
    int width = kW, height = kH;               // the one size it streams at
    int row_padding_bytes = 0;                 // after each row of pixels (bytesperline)
  };
  static constexpr size_t kMjpegBufferBytes = 1 << 16;
  std::vector<Node> nodes;
  bool unplugged = false;
  // Simulated time: a scripted frame is visible once now_ns reaches its timestamp; waiting in
  // poll() moves time forward (up to the timeout).
  int64_t now_ns = 0;

  Node& add(const std::string& path, uint32_t fourcc) {
    nodes.push_back({path,
                     fourcc,
                     {},
                     {},
                     {},
                     false,
                     false,
                     0,
                     {},
                     {},
                     false,
                     0,
                     false,
                     V4L2_META_FMT_UVC,
                     0,
                     kW,
                     kH,
                     0});
    return nodes.back();
  }
  static size_t bytes_per_line(const Node& n) {
    return static_cast<size_t>(n.width * 2 + n.row_padding_bytes);
  }
  static size_t buffer_bytes(const Node& n) {
    if (n.metadata) return kMetadataBufferBytes;
    return n.fourcc == V4L2_PIX_FMT_MJPEG ? kMjpegBufferBytes
                                          : bytes_per_line(n) * static_cast<size_t>(n.height);
  }
  static constexpr size_t kMetadataBufferBytes = 1024;
  Node* node(int fd) {
    return fd >= 3 && fd - 3 < static_cast<int>(nodes.size()) ? &nodes[fd - 3] : nullptr;
  }

  int open(const char* path, int) override {
    for (size_t i = 0; i < nodes.size() && !unplugged; ++i) {
      if (nodes[i].path == path) {
        nodes[i].open = true;
        nodes[i].wedged = false;
        nodes[i].qbuf_broken = false;
        ++nodes[i].opens;
        return static_cast<int>(i) + 3;
      }
    }
    errno = ENOENT;
    return -1;
  }
  int close(int fd) override {
    if (Node* n = node(fd)) n->open = false;
    return 0;
  }
  int fail(int e) {
    errno = e;
    return -1;
  }
  int ioctl(int fd, unsigned long request, void* arg) override {
    Node* n = node(fd);
    if (n == nullptr) return fail(EBADF);
    if (unplugged && request != VIDIOC_STREAMOFF) return fail(ENODEV);
    switch (request) {
      case VIDIOC_QUERYCAP: {
        auto* cap = static_cast<v4l2_capability*>(arg);
        cap->device_caps =
            (n->metadata ? V4L2_CAP_META_CAPTURE : V4L2_CAP_VIDEO_CAPTURE) | V4L2_CAP_STREAMING;
        cap->capabilities = cap->device_caps | V4L2_CAP_DEVICE_CAPS;
        return 0;
      }
      case VIDIOC_ENUM_FMT: {
        auto* f = static_cast<v4l2_fmtdesc*>(arg);
        if (n->metadata || f->index > n->also_offers.size()) return fail(EINVAL);
        f->pixelformat = f->index == 0 ? n->fourcc : n->also_offers[f->index - 1];
        return 0;
      }
      case VIDIOC_S_FMT: {
        auto* f = static_cast<v4l2_format*>(arg);
        if (n->metadata) {  // uvcvideo: the camera's own format if asked for, else UVCH
          if (f->fmt.meta.dataformat != n->meta_format) f->fmt.meta.dataformat = V4L2_META_FMT_UVC;
          f->fmt.meta.buffersize = kMetadataBufferBytes;
          return 0;
        }
        f->fmt.pix.pixelformat = n->fourcc;  // the nearest it has
        f->fmt.pix.width = static_cast<uint32_t>(n->width);
        f->fmt.pix.height = static_cast<uint32_t>(n->height);
        f->fmt.pix.bytesperline =
            n->fourcc == V4L2_PIX_FMT_MJPEG ? 0 : static_cast<uint32_t>(bytes_per_line(*n));
        return 0;
      }
      case VIDIOC_REQBUFS: {
        auto* r = static_cast<v4l2_requestbuffers*>(arg);
        r->count = 3;
        n->queued.clear();
        n->buffers.assign(3, std::vector<uint8_t>(buffer_bytes(*n), 0));
        return 0;
      }
      case VIDIOC_QUERYBUF: {
        auto* b = static_cast<v4l2_buffer*>(arg);
        b->length = static_cast<uint32_t>(buffer_bytes(*n));
        b->m.offset = b->index * 4096;
        return 0;
      }
      case VIDIOC_QBUF:
        if (n->qbuf_broken) return fail(EIO);
        if (n->qbuf_failures > 0) {
          --n->qbuf_failures;
          return fail(EIO);
        }
        n->queued.push_back(static_cast<int>(static_cast<v4l2_buffer*>(arg)->index));
        return 0;
      case VIDIOC_STREAMON:
      case VIDIOC_STREAMOFF:
        return 0;
      case VIDIOC_DQBUF: {
        if (n->script.empty() || n->queued.empty() || n->script.front().t_ns > now_ns) {
          return fail(EAGAIN);
        }
        const Event e = n->script.front();
        n->script.pop_front();
        if (e.kind == Event::kEintr) return fail(EINTR);
        if (e.kind == Event::kEagain) return fail(EAGAIN);
        if (e.kind == Event::kUnplug) {
          unplugged = true;
          return fail(ENODEV);
        }
        auto* b = static_cast<v4l2_buffer*>(arg);
        b->index = static_cast<uint32_t>(n->queued.front());
        n->queued.pop_front();
        std::vector<uint8_t>& mem = n->buffers[b->index];
        b->bytesused = static_cast<uint32_t>(buffer_bytes(*n));
        b->sequence = e.sequence >= 0 ? static_cast<uint32_t>(e.sequence) : n->frames;
        ++n->frames;
        if (n->metadata) {
          b->bytesused = static_cast<uint32_t>(write_metadata(*n, e, mem.data()));
        } else if (n->fourcc == V4L2_PIX_FMT_MJPEG) {
          const std::vector<uint8_t>& jpeg = n->jpeg[e.fill % n->jpeg.size()];
          std::memcpy(mem.data(), jpeg.data(), jpeg.size());
          b->bytesused = static_cast<uint32_t>(jpeg.size());
        } else {
          std::fill(mem.begin(), mem.end(), uint8_t{0xee});  // what padding holds: not pixels
          for (int i = 0; i < n->width * n->height; ++i) {
            uint8_t* p = &mem[bytes_per_line(*n) * static_cast<size_t>(i / n->width) +
                              2 * static_cast<size_t>(i % n->width)];
            if (n->fourcc == V4L2_PIX_FMT_Z16) {
              const uint16_t v = static_cast<uint16_t>(e.fill * 100 + i);
              std::memcpy(p, &v, 2);
            } else {
              p[0] = static_cast<uint8_t>(e.fill + i % 2);  // Y
              p[1] = 128;                                   // U or V
            }
          }
        }
        b->flags = e.kind == Event::kErrorFlag ? V4L2_BUF_FLAG_ERROR : 0;
        b->timestamp.tv_sec = e.t_ns / 1000000000;
        b->timestamp.tv_usec = (e.t_ns % 1000000000) / 1000;
        return 0;
      }
      default:
        return fail(EINVAL);
    }
  }
  // One uvc_meta_buf block as uvcvideo writes it: arrival ns, USB frame number, then the payload
  // header (length, flags PTS|SCR, PTS, SCR) and, in D4XX, Intel's capture timing block.
  static size_t write_metadata(const Node& n, const Event& e, uint8_t* out) {
    auto put32 = [](uint8_t* p, uint32_t v) { put_le(&p, v); };
    const bool d4xx = n.meta_format == V4L2_META_FMT_D4XX;
    const uint8_t length = d4xx ? 12 + 40 : 12;
    std::memset(out, 0, 10 + length);
    const uint64_t ns = static_cast<uint64_t>(e.t_ns);
    std::memcpy(out, &ns, 8);
    out[10] = length;
    out[11] = 0x04 | 0x08;
    put32(out + 12, e.pts);
    if (d4xx) {
      uint8_t* timing = out + 10 + 12;
      put32(timing, 0x80000001u);  // capture timing
      put32(timing + 4, 40);
      put32(timing + 8, 1);     // version
      put32(timing + 12, 0x1);  // the frame counter is valid
      put32(timing + 16, e.frame_counter);
    }
    return 10 + length;
  }
  void* mmap(size_t, int fd, off_t offset) override {
    Node* n = node(fd);
    if (n == nullptr) return MAP_FAILED;
    return n->buffers[static_cast<size_t>(offset / 4096)].data();
  }
  int munmap(void*, size_t) override { return 0; }
  int poll(int fd, int timeout_ms) override {
    Node* n = node(fd);
    if (unplugged) return fail(ENODEV);
    if (n == nullptr || n->script.empty() || n->wedged) {
      now_ns += timeout_ms * 1000000LL;
      return 0;  // nothing scripted: a timeout
    }
    const int64_t due = n->script.front().t_ns;
    if (due <= now_ns) return 1;
    if (due <= now_ns + timeout_ms * 1000000LL) {
      now_ns = due;
      return 1;
    }
    now_ns += timeout_ms * 1000000LL;
    return 0;
  }
};

inline Event frame(int64_t t_ms, uint8_t fill) { return {Event::kFrame, t_ms * kMs, fill}; }

}  // namespace rgbdtam::testing

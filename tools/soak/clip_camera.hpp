#pragma once
// A V4L2 depth camera (a Z16 node and a YUYV or MJPEG node) behind the V4l2Io seam that plays the
// committed clip in a loop at a fixed rate in real time, and is unplugged for given intervals:
// every call then fails as an unplugged device does (ENODEV, ENOENT on open). Everything is
// allocated at construction, so the soak measures the runtime's memory, not the fake's.
#include <linux/videodev2.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "rgbdtam/hal/v4l2_source.hpp"

namespace rgbdtam::testing {

class ClipCamera : public V4l2Io {
 public:
  struct Outage {
    double at_s, for_s;  // after the start
  };
  // The clip's frames (grey, raw depth), played at fps from now on.
  ClipCamera(std::vector<std::vector<uint8_t>> gray, std::vector<std::vector<uint16_t>> depth,
             int width, int height, double fps, std::vector<Outage> outages);

  // The clip in `dir` decoded once (grey, raw depth, and optionally the colour stamps); false
  // when it cannot be read.
  static bool load(const std::string& dir, std::vector<std::vector<uint8_t>>* gray,
                   std::vector<std::vector<uint16_t>>* depth,
                   std::vector<int64_t>* stamps_ns = nullptr);
  // Which clip frame a delivered buffer's timestamp is (frames count on past the clip's end).
  int64_t frame_of(int64_t timestamp_ns) const {
    return (timestamp_ns - start_ns_ + period_ns_ / 2) / period_ns_;
  }
  // Before opening: the colour node sends these (one JPEG per clip frame) as MJPEG.
  void send_mjpeg(std::vector<std::vector<uint8_t>> jpeg);
  // Before opening: the next frame is due once the reader has given back every buffer, so the
  // reader drives the clock and sees every frame, however slow the machine (stamps stay fps
  // apart).
  void drive_by_reader() { driven_by_reader_ = true; }

  int open(const char* path, int flags) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(size_t length, int fd, off_t offset) override;
  int munmap(void* address, size_t length) override;
  int poll(int fd, int timeout_ms) override;

  uint64_t frames_played() const { return played_.load(); }
  int outages_started() const { return outages_started_.load(); }

 private:
  static constexpr int kBuffers = 4;
  struct Node {
    uint32_t fourcc;
    bool open = false;
    int64_t next_frame = 0;  // the first not yet delivered
    std::vector<uint8_t> buffers[kBuffers];
    int queued[kBuffers] = {};
    int queued_count = 0;
  };
  bool unplugged(int64_t now_ns);
  static bool reader_holds_none(const Node& n) { return n.queued_count == kBuffers; }
  int64_t due_ns(int64_t frame) const;
  Node* node(int fd);
  // The frame's bytes into a buffer; how many.
  size_t fill(const Node& n, int64_t frame, std::vector<uint8_t>* out) const;

  std::vector<std::vector<uint8_t>> gray_;
  std::vector<std::vector<uint16_t>> depth_;
  std::vector<std::vector<uint8_t>> jpeg_;
  int width_, height_;
  int64_t period_ns_;
  int64_t start_ns_;
  std::vector<Outage> outages_;
  Node nodes_[2];  // fd 3: depth, fd 4: colour
  std::atomic<uint64_t> played_{0};
  std::atomic<int> outages_started_{0};
  int last_outage_ = -1;
  bool driven_by_reader_ = false;
  std::mutex mutex_;  // the sensor's thread and a reopen may call at once
};

}  // namespace rgbdtam::testing

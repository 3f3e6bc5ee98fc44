#pragma once
// What the monitor has received over the pose link, kept for the terminal line and the live
// page: counters, the last ODOMETRY, the trajectory from above, the STATUSTEXT log and whether an
// autopilot is there. Host-side: this allocates (the trajectory grows with the run).
#include <cstdint>
#include <cstdio>
#include <deque>
#include <string>
#include <vector>

#include "rgbdtam/runtime/mavlink.hpp"

namespace rgbdtam {

// A received body position in the link's local FRD frame; valid = false for a lost frame.
struct MonitorPoint {
  float x_m, y_m, z_m;
  bool valid;
  uint8_t reset_counter;
};

struct MonitorText {
  double time_s;  // since the monitor started
  uint8_t severity;
  std::string text;
};

enum class MonitorEvent { kNone, kValidPose, kText };

class MonitorState {
 public:
  static constexpr size_t kMaxTexts = 200;
  explicit MonitorState(int64_t start_ns) : start_ns_(start_ns), window_start_ns_(start_ns) {}

  MonitorEvent on_frame(const mavlink::Frame& f, int64_t now_ns);
  // Once per loop: the rate over the last second.
  void tick(int64_t now_ns, const mavlink::DecoderCounters& link);
  const char* state_name() const;
  // The state as one JSON object; the trajectory from point `since` on (the page asks for what
  // it has not drawn yet).
  void write_json(std::FILE* out, size_t since) const;

  uint64_t odometry = 0, valid = 0, lost = 0, heartbeats = 0, status_texts = 0;
  // ODOMETRY claiming a pose it does not carry (not finite, no unit quaternion, quality beyond
  // 100) or older than the last valid one: neither valid nor lost.
  uint64_t malformed = 0;
  mavlink::Odometry last;
  uint8_t system_status = 0;
  double rate_hz = 0;
  mavlink::DecoderCounters link;
  std::string autopilot = "not heard";
  // The firmware's latency from a frame's arrival to its ODOMETRY so far (NAMED_VALUE_FLOAT
  // lat_med_ms, lat_p95_ms, lat_max_ms, once a second); negative: not received.
  float latency_median_ms = -1, latency_p95_ms = -1, latency_max_ms = -1;
  std::vector<MonitorPoint> track;
  std::deque<MonitorText> texts;

 private:
  int64_t start_ns_;
  int64_t window_start_ns_;
  uint64_t window_count_ = 0;
  uint64_t saved_until_usec_ = 0;  // the newest valid pose's time_usec
  mavlink::StatusTextJoiner joiner_;
};

}  // namespace rgbdtam

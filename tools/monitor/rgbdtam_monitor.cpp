// Host-side monitor of the pose link: receives MAVLink over UDP, shows pose, rate, tracking
// state and link counters live, and can save the received poses as a TUM trajectory (camera
// poses, undoing the board's body-from-camera extrinsics) to evaluate what the robot saw.
//
//   rgbdtam-monitor [--port 14550] [--board board/<name>] [--save trajectory.txt]
//                   [--idle-exit seconds] [--quiet]
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>

#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/hal/udp_link.hpp"
#include "rgbdtam/runtime/pose_link.hpp"
#include "run_job.hpp"

namespace rgbdtam {
namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

struct Stats {
  uint64_t odometry = 0, valid = 0, lost = 0, heartbeats = 0, status_texts = 0;
  mavlink::Odometry last;
  uint8_t system_status = 0;
  char last_text[mavlink::kMaxStatusTextChars + 1] = "";
  int64_t window_start_ns = 0;
  uint64_t window_count = 0;
  double rate_hz = 0;
};

const char* state_name(const Stats& s) {
  if (s.odometry == 0) return "waiting";
  return s.last.quality < 0 ? "LOST" : "tracking";
}

int monitor(int argc, char** argv) {
  uint16_t port = 14550;
  const char* board_dir = nullptr;
  const char* save = nullptr;
  double idle_exit_s = 0;
  bool quiet = false;
  for (int i = 0; i < argc; ++i) {
    const bool has = i + 1 < argc;
    if (std::strcmp(argv[i], "--port") == 0 && has) {
      port = static_cast<uint16_t>(std::atoi(argv[++i]));
    } else if (std::strcmp(argv[i], "--board") == 0 && has) {
      board_dir = argv[++i];
    } else if (std::strcmp(argv[i], "--save") == 0 && has) {
      save = argv[++i];
    } else if (std::strcmp(argv[i], "--idle-exit") == 0 && has) {
      idle_exit_s = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--quiet") == 0) {
      quiet = true;
    } else {
      std::fprintf(stderr,
                   "usage: rgbdtam-monitor [--port 14550] [--board board/<name>] [--save "
                   "trajectory.txt] [--idle-exit seconds] [--quiet]\n");
      return 2;
    }
  }
  Board board;  // identity extrinsics unless a board says otherwise
  if (board_dir != nullptr) {
    const Status s = load_board(board_dir, &board);
    if (!s.is_ok()) {
      std::fprintf(stderr, "rgbdtam-monitor: %s\n", s.message());
      return 1;
    }
  }
  UdpLink udp;
  Status s = udp.open(nullptr, 0, port);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam-monitor: %s\n", s.message());
    return 1;
  }
  TrajectoryWriter writer;
  if (save != nullptr && !(s = writer.open(save)).is_ok()) {
    std::fprintf(stderr, "rgbdtam-monitor: %s\n", s.message());
    return 1;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  if (!quiet) std::fprintf(stderr, "listening on UDP port %u\n", port);
  mavlink::Decoder decoder;
  mavlink::StatusTextJoiner joiner;
  Stats st;
  uint8_t buf[2048];
  int64_t last_rx_ns = 0, last_print_ns = 0;
  while (g_stop == 0) {
    const size_t n = udp.receive(buf, sizeof(buf));
    const int64_t now = monotonic_ns();
    if (n == 0) {
      if (idle_exit_s > 0 && st.odometry > 0 && (now - last_rx_ns) * 1e-9 > idle_exit_s) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    } else {
      last_rx_ns = now;
    }
    decoder.feed_all(buf, n, [&](const mavlink::Frame& f) {
      if (f.message_id == mavlink::kOdometry.id) {
        mavlink::unpack(f.payload, f.length, &st.last);
        ++st.odometry;
        ++st.window_count;
        if (st.last.quality < 0) {
          ++st.lost;
          return;
        }
        ++st.valid;
        if (save != nullptr) {
          PoseEstimate p;
          p.timestamp_ns = static_cast<int64_t>(st.last.time_usec) * 1000;
          p.T_w_c = camera_pose_of(st.last, board.T_b_c);
          p.flags = kPoseValid;
          (void)writer.write(p);
        }
      } else if (f.message_id == mavlink::kHeartbeat.id) {
        mavlink::Heartbeat hb;
        mavlink::unpack(f.payload, f.length, &hb);
        st.system_status = hb.system_status;
        ++st.heartbeats;
      } else if (f.message_id == mavlink::kStatusText.id) {
        mavlink::StatusText t;
        mavlink::unpack(f.payload, f.length, &t);
        const char* whole = joiner.add(t);
        if (whole == nullptr) return;  // more chunks to come
        std::snprintf(st.last_text, sizeof(st.last_text), "%s", whole);
        ++st.status_texts;
        if (!quiet) {
          std::fprintf(stderr, "\nSTATUSTEXT (severity %u): %s\n", t.severity, st.last_text);
        }
      }
    });
    if (now - st.window_start_ns >= 1'000'000'000) {
      st.rate_hz = st.window_count / ((now - st.window_start_ns) * 1e-9);
      st.window_start_ns = now;
      st.window_count = 0;
    }
    if (!quiet && now - last_print_ns >= 250'000'000) {
      last_print_ns = now;
      const mavlink::DecoderCounters& d = decoder.counters();
      std::fprintf(stderr,
                   "\r%-8s %5.1f Hz  odometry %llu (lost %llu)  x %+.3f y %+.3f z %+.3f m  "
                   "quality %d  resets %u  heartbeats %llu  crc errors %llu  seq gaps %llu   ",
                   state_name(st), st.rate_hz, static_cast<unsigned long long>(st.odometry),
                   static_cast<unsigned long long>(st.lost), static_cast<double>(st.last.x),
                   static_cast<double>(st.last.y), static_cast<double>(st.last.z), st.last.quality,
                   st.last.reset_counter, static_cast<unsigned long long>(st.heartbeats),
                   static_cast<unsigned long long>(d.crc_errors),
                   static_cast<unsigned long long>(d.lost_frames));
    }
  }
  const mavlink::DecoderCounters& d = decoder.counters();
  std::printf(
      "%sodometry %llu (valid %llu, lost %llu), heartbeats %llu, statustext %llu, crc "
      "errors %llu, sequence gaps %llu, bytes skipped %llu\n",
      quiet ? "" : "\n", static_cast<unsigned long long>(st.odometry),
      static_cast<unsigned long long>(st.valid), static_cast<unsigned long long>(st.lost),
      static_cast<unsigned long long>(st.heartbeats),
      static_cast<unsigned long long>(st.status_texts),
      static_cast<unsigned long long>(d.crc_errors), static_cast<unsigned long long>(d.lost_frames),
      static_cast<unsigned long long>(d.bytes_skipped));
  if (save != nullptr) {
    s = writer.close();
    if (!s.is_ok()) {
      std::fprintf(stderr, "rgbdtam-monitor: %s\n", s.message());
      return 1;
    }
    std::printf("saved %llu poses to %s\n", static_cast<unsigned long long>(st.valid), save);
  }
  return 0;
}

}  // namespace
}  // namespace rgbdtam

int main(int argc, char** argv) { return rgbdtam::monitor(argc - 1, argv + 1); }

// Host-side monitor of the pose link: receives MAVLink over UDP, shows pose, rate, tracking
// state and link counters live (in the terminal, and with --http as a page in the browser), and
// can save the received poses as a TUM trajectory (camera poses, undoing the board's
// body-from-camera extrinsics) to evaluate what the robot saw.
//
//   rgbdtam-monitor [--port 14550] [--board board/<name>] [--save trajectory.txt]
//                   [--http 127.0.0.1:8080] [--idle-exit seconds] [--quiet]
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <thread>

#include "config_files.hpp"
#include "monitor_http.hpp"
#include "monitor_state.hpp"
#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/hal/udp_link.hpp"
#include "rgbdtam/runtime/pose_link.hpp"
#include "run_job.hpp"

namespace rgbdtam {
namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

int monitor(int argc, char** argv) {
  uint16_t port = 14550;
  const char* board_dir = nullptr;
  const char* save = nullptr;
  const char* http_address = nullptr;
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
    } else if (std::strcmp(argv[i], "--http") == 0 && has) {
      http_address = argv[++i];
    } else if (std::strcmp(argv[i], "--idle-exit") == 0 && has) {
      idle_exit_s = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--quiet") == 0) {
      quiet = true;
    } else {
      std::fprintf(stderr,
                   "usage: rgbdtam-monitor [--port 14550] [--board board/<name>] [--save "
                   "trajectory.txt] [--http 127.0.0.1:8080] [--idle-exit seconds] [--quiet]\n");
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
  MonitorState st(monotonic_ns());
  std::mutex st_lock;  // the page's requests read the state on the HTTP server's thread
  MonitorHttp http;
  if (http_address != nullptr && !(s = http.start(http_address, &st, &st_lock)).is_ok()) {
    std::fprintf(stderr, "rgbdtam-monitor: %s\n", s.message());
    return 1;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  if (!quiet) std::fprintf(stderr, "listening on UDP port %u\n", port);
  if (http_address != nullptr) std::printf("live page: http://%s/\n", http_address);
  std::fflush(stdout);
  mavlink::Decoder decoder;
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
    std::lock_guard<std::mutex> guard(st_lock);
    decoder.feed_all(buf, n, [&](const mavlink::Frame& f) {
      const MonitorEvent event = st.on_frame(f, now);
      if (event == MonitorEvent::kValidPose && save != nullptr) {
        PoseEstimate p;
        p.timestamp_ns = static_cast<int64_t>(st.last.time_usec) * 1000;
        p.T_w_c = camera_pose_of(st.last, board.T_b_c);
        p.flags = kPoseValid;
        (void)writer.write(p);
      } else if (event == MonitorEvent::kText && !quiet) {
        const MonitorText& t = st.texts.back();
        std::fprintf(stderr, "\nSTATUSTEXT (severity %u): %s\n", t.severity, t.text.c_str());
      }
    });
    st.tick(now, decoder.counters());
    if (!quiet && now - last_print_ns >= 250'000'000) {
      last_print_ns = now;
      const mavlink::DecoderCounters& d = decoder.counters();
      std::fprintf(stderr,
                   "\r%-8s %5.1f Hz  odometry %llu (lost %llu)  x %+.3f y %+.3f z %+.3f m  "
                   "quality %d  resets %u  heartbeats %llu  crc errors %llu  seq gaps %llu   ",
                   st.state_name(), st.rate_hz, static_cast<unsigned long long>(st.odometry),
                   static_cast<unsigned long long>(st.lost), static_cast<double>(st.last.x),
                   static_cast<double>(st.last.y), static_cast<double>(st.last.z), st.last.quality,
                   st.last.reset_counter, static_cast<unsigned long long>(st.heartbeats),
                   static_cast<unsigned long long>(d.crc_errors),
                   static_cast<unsigned long long>(d.lost_frames));
    }
  }
  const mavlink::DecoderCounters& d = decoder.counters();
  std::printf(
      "%sodometry %llu (valid %llu, lost %llu, malformed %llu), heartbeats %llu, statustext "
      "%llu, crc errors %llu, sequence gaps %llu, bytes skipped %llu\n",
      quiet ? "" : "\n", static_cast<unsigned long long>(st.odometry),
      static_cast<unsigned long long>(st.valid), static_cast<unsigned long long>(st.lost),
      static_cast<unsigned long long>(st.malformed), static_cast<unsigned long long>(st.heartbeats),
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

#include "firmware_monitor.hpp"

#include <gtest/gtest.h>

#include "test_paths.hpp"

namespace rgbdtam {
namespace testing {

void Monitor::drain(const SE3& T_b_c) {
  uint8_t buf[2048];
  for (size_t n; (n = udp.receive(buf, sizeof(buf))) > 0;) {
    decoder.feed_all(buf, n, [&](const mavlink::Frame& f) {
      if (f.message_id == mavlink::kOdometry.id) {
        mavlink::Odometry o;
        mavlink::unpack(f.payload, f.length, &o);
        ++odometry;
        odometry_messages.push_back(o);
        if (o.quality < 0) {
          ++lost;
        } else {
          poses.push_back({o.time_usec * 1e-6, camera_pose_of(o, T_b_c)});
        }
      } else if (f.message_id == mavlink::kObstacleDistance.id) {
        obstacles.emplace_back();
        mavlink::unpack(f.payload, f.length, &obstacles.back());
      } else if (f.message_id == mavlink::kHeartbeat.id) {
        ++heartbeats;
      } else if (f.message_id == mavlink::kStatusText.id) {
        mavlink::StatusText t;
        mavlink::unpack(f.payload, f.length, &t);
        if (const char* whole = joiner.add(t)) texts.emplace_back(whole);
      }
      if (on_frame) on_frame(f);
    });
  }
}

void run_board(Monitor* monitor, RunJob* job, std::vector<std::string> overrides,
               const std::string& board_dir, bool every_frame) {
  ASSERT_TRUE(monitor->udp.open(nullptr, 0, 0).is_ok());
  overrides.push_back("link.udp_remote=127.0.0.1:" + std::to_string(monitor->udp.local_port()));
  static std::vector<std::string> keep;  // the options point into these
  keep = overrides;
  static std::string board;
  board = board_dir.empty() ? source_path("board/host-emulation") : board_dir;
  RunOptions options;
  options.board_dir = board.c_str();
  for (const std::string& o : keep)
    options.board_overrides[options.board_override_count++] = o.c_str();
  options.progress = false;
  options.replay_every_frame = every_frame;
  const Status s = job->init(options);
  ASSERT_TRUE(s.is_ok()) << s.message();
  ASSERT_TRUE(job->start().is_ok());
  while (job->step()) {
    monitor->drain(job->board().T_b_c);
    if (monitor->on_step) monitor->on_step(*job);
  }
  job->finish();
  monitor->drain(job->board().T_b_c);
}

}  // namespace testing
}  // namespace rgbdtam

#pragma once
// The firmware run in-process (RunJob) with its MAVLink link pointed at this test acting as the
// monitor on UDP loopback: what a flight controller would receive, decoded.
#include <functional>
#include <string>
#include <vector>

#include "rgbdtam/core/evaluation.hpp"
#include "rgbdtam/hal/udp_link.hpp"
#include "rgbdtam/runtime/mavlink.hpp"
#include "rgbdtam/runtime/pose_link.hpp"
#include "run_job.hpp"

namespace rgbdtam {
namespace testing {

struct Monitor {
  UdpLink udp;
  mavlink::Decoder decoder;
  std::vector<StampedPose> poses;
  int odometry = 0, lost = 0, heartbeats = 0;
  std::vector<std::string> texts;
  std::vector<mavlink::ObstacleDistance> obstacles;
  mavlink::StatusTextJoiner joiner;
  std::vector<mavlink::Odometry> odometry_messages;
  // A test playing the autopilot: every frame received, and each step after the drain.
  std::function<void(const mavlink::Frame&)> on_frame;
  std::function<void(const RunJob&)> on_step;
  // Decodes what has arrived; poses in the camera frame (T_b_c: the board's mounting).
  void drain(const SE3& T_b_c);
};

// Runs a board (board/host-emulation unless named) with its link pointed at the monitor.
// every_frame: a replay sensor drops no frame (RunOptions::replay_every_frame).
void run_board(Monitor* monitor, RunJob* job, std::vector<std::string> overrides,
               const std::string& board_dir = "", bool every_frame = false);

}  // namespace testing
}  // namespace rgbdtam

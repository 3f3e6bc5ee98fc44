// The monitor counts what it receives as an autopilot would take it: an ODOMETRY claiming a pose
// it does not carry (spoofed or damaged: NaN or inf position, a zero or NaN quaternion, quality
// beyond 100) or older than the last valid one is malformed, never drawn, shown or saved.
#include <gtest/gtest.h>

#include <cmath>

#include "monitor_state.hpp"

namespace rgbdtam {
namespace {

mavlink::Odometry pose_at(uint64_t time_usec) {
  mavlink::Odometry o;
  o.time_usec = time_usec;
  o.x = 1.0f;
  o.q[0] = 1.0f;
  o.quality = 80;
  return o;
}

MonitorEvent receive(MonitorState* state, const mavlink::Odometry& o) {
  mavlink::Encoder encoder(1, 197);
  uint8_t bytes[mavlink::kMaxFrameBytes];
  const int n = encoder.encode(o, bytes);
  mavlink::Decoder decoder;
  MonitorEvent event = MonitorEvent::kNone;
  int frames = 0;
  decoder.feed_all(bytes, static_cast<size_t>(n), [&](const mavlink::Frame& f) {
    event = state->on_frame(f, 0);
    ++frames;
  });
  EXPECT_EQ(frames, 1);
  return event;
}

TEST(MonitorState, OdometryThatCarriesNoUsablePoseIsMalformedNotValid) {
  MonitorState state(0);
  EXPECT_EQ(receive(&state, pose_at(1000)), MonitorEvent::kValidPose);
  mavlink::Odometry lost = pose_at(2000);
  lost.quality = -1;
  lost.x = NAN;
  lost.q[0] = NAN;
  EXPECT_EQ(receive(&state, lost), MonitorEvent::kNone);

  mavlink::Odometry spoofed[6] = {pose_at(3000), pose_at(3000), pose_at(3000),
                                  pose_at(3000), pose_at(3000), pose_at(500)};
  spoofed[0].x = NAN;
  spoofed[1].y = INFINITY;
  spoofed[2].q[0] = 0.0f;  // no rotation at all
  spoofed[3].q[1] = NAN;
  spoofed[4].quality = 101;
  // spoofed[5]: older than the last valid pose
  for (const mavlink::Odometry& o : spoofed) {
    EXPECT_EQ(receive(&state, o), MonitorEvent::kNone);
  }
  EXPECT_EQ(receive(&state, pose_at(4000)), MonitorEvent::kValidPose);
  EXPECT_EQ(state.odometry, 9u);
  EXPECT_EQ(state.valid, 2u);
  EXPECT_EQ(state.lost, 1u);
  EXPECT_EQ(state.malformed, 6u);
  EXPECT_EQ(state.track.size(), 3u) << "malformed messages are not drawn";
  EXPECT_EQ(state.last.time_usec, 4000u);
}

}  // namespace
}  // namespace rgbdtam

// The pose link: ODOMETRY contents (frames, velocities, covariance, quality, reset counter),
// and the whole path over UDP on loopback and over a pseudo-terminal pair at 921600 and
// 115200 baud, with the rate policy and a transport that never blocks.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

#include "rgbdtam/hal/serial_link.hpp"
#include "rgbdtam/hal/udp_link.hpp"
#include "rgbdtam/runtime/pose_link.hpp"

namespace rgbdtam {
namespace {

constexpr int64_t kFrameNs = 33333333;  // 30 Hz

// Camera (x right, y down, z forward) to body front-right-down.
SE3 body_from_camera() {
  Matrix3d R;
  R << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  return SE3(Eigen::Quaterniond(R), Vector3d(0.1, 0, -0.05));
}

PoseEstimate pose_at(int i, const Vector3d& camera_velocity_m_s) {
  PoseEstimate p;
  p.sequence = static_cast<uint32_t>(i);
  p.timestamp_ns = 1000000000 + i * kFrameNs;
  p.T_w_c = SE3(Eigen::Quaterniond::Identity(), camera_velocity_m_s * (i * kFrameNs * 1e-9));
  p.flags = kPoseValid;
  p.overlap = 0.9f;
  p.information = Eigen::Matrix<double, 6, 6>::Identity() * 1e6;
  return p;
}

TEST(PoseLink, OdometryIsInTheBodyFrameWithVelocitiesCovarianceAndHealth) {
  PoseLinkConfig config;
  config.T_b_c = body_from_camera();
  PoseLink link;
  link.init(config, nullptr);
  const Vector3d forward_in_camera(0, 0, 0.6);  // 0.6 m/s along the optical axis
  (void)link.odometry_of(pose_at(0, forward_in_camera));
  PoseEstimate p = pose_at(1, forward_in_camera);
  p.information(0, 0) = 4e6;  // camera x (body y) is known better
  const mavlink::Odometry o = link.odometry_of(p);
  EXPECT_NEAR(o.x, 0.02, 1e-6);  // body x forward: 0.6 m/s * 1/30 s
  EXPECT_NEAR(o.y, 0.0, 1e-6);
  EXPECT_NEAR(o.vx, 0.6, 1e-4);
  EXPECT_NEAR(o.vy, 0.0, 1e-5);
  EXPECT_NEAR(o.q[0], 1.0, 1e-6);
  EXPECT_NEAR(o.yawspeed, 0.0, 1e-6);
  EXPECT_NEAR(o.pose_covariance[0], 1e-6, 1e-12);     // x x
  EXPECT_NEAR(o.pose_covariance[6], 0.25e-6, 1e-12);  // y y
  EXPECT_EQ(o.quality, 90);
  EXPECT_EQ(o.estimator_type, mavlink::kMavEstimatorTypeVision);
  EXPECT_EQ(o.frame_id, mavlink::kMavFrameLocalFrd);
  EXPECT_TRUE(std::isnan(o.velocity_covariance[0]));

  // A lost frame: quality -1, no pose. The next valid one has no velocity (no history).
  PoseEstimate lost = pose_at(2, forward_in_camera);
  lost.flags = kLost;
  const mavlink::Odometry l = link.odometry_of(lost);
  EXPECT_EQ(l.quality, -1);
  EXPECT_TRUE(std::isnan(l.x));
  PoseEstimate after = pose_at(3, forward_in_camera);
  after.reset_counter = 1;
  const mavlink::Odometry a = link.odometry_of(after);
  EXPECT_EQ(a.reset_counter, 1);
  EXPECT_TRUE(std::isnan(a.vx));
  EXPECT_NEAR(a.x, 0.06, 1e-6);

  // A pose flagged valid that is not finite goes out as lost, never with a quality.
  PoseEstimate broken = pose_at(4, forward_in_camera);
  broken.T_w_c = SE3(Eigen::Quaterniond::Identity(), Vector3d(NAN, 0, 0));
  const mavlink::Odometry b = link.odometry_of(broken);
  EXPECT_EQ(b.quality, -1);
  EXPECT_TRUE(std::isnan(b.x) && std::isnan(b.q[0]));
}

// Collects every frame a decoder finds in a byte source.
struct Received {
  mavlink::Decoder decoder;
  std::vector<mavlink::Odometry> odometry;
  int heartbeats = 0, status_texts = 0;
  std::vector<mavlink::StatusText> texts;
  std::vector<mavlink::Timesync> timesync;
  std::vector<mavlink::SetGpsGlobalOrigin> origins;
  std::vector<mavlink::NamedValueFloat> values;
  void take(const uint8_t* bytes, size_t n) {
    decoder.feed_all(bytes, n, [this](const mavlink::Frame& f) {
      if (f.message_id == mavlink::kOdometry.id) {
        odometry.emplace_back();
        mavlink::unpack(f.payload, f.length, &odometry.back());
      } else if (f.message_id == mavlink::kHeartbeat.id) {
        ++heartbeats;
      } else if (f.message_id == mavlink::kStatusText.id) {
        ++status_texts;
        texts.emplace_back();
        mavlink::unpack(f.payload, f.length, &texts.back());
      } else if (f.message_id == mavlink::kTimesync.id) {
        timesync.emplace_back();
        mavlink::unpack(f.payload, f.length, &timesync.back());
      } else if (f.message_id == mavlink::kSetGpsGlobalOrigin.id) {
        origins.emplace_back();
        mavlink::unpack(f.payload, f.length, &origins.back());
      } else if (f.message_id == mavlink::kNamedValueFloat.id) {
        values.emplace_back();
        mavlink::unpack(f.payload, f.length, &values.back());
      }
    });
  }
};

TEST(PoseLink, EveryOdometryArrivesOverUdpOnLoopback) {
  UdpLink receiver, sender;
  ASSERT_TRUE(receiver.open(nullptr, 0, 0).is_ok());
  ASSERT_TRUE(sender.open("127.0.0.1", receiver.local_port(), 0).is_ok());
  PoseLink link;
  link.init(PoseLinkConfig{}, &sender);
  Received rx;
  uint8_t buf[2048];
  constexpr int kPoses = 300;
  for (int i = 0; i < kPoses; ++i) {
    const int64_t now = i * kFrameNs;
    link.tick(now, mavlink::kMavStateActive);
    link.on_pose(pose_at(i, Vector3d(0.1, 0, 0)), now);
    if (i == 100) link.on_status(mavlink::kMavSeverityWarning, "tracking lost", now);
    for (size_t n; (n = receiver.receive(buf, sizeof(buf))) > 0;) rx.take(buf, n);
  }
  for (int spin = 0; spin < 100; ++spin) {
    for (size_t n; (n = receiver.receive(buf, sizeof(buf))) > 0;) rx.take(buf, n);
  }
  ASSERT_EQ(rx.odometry.size(), static_cast<size_t>(kPoses));
  EXPECT_EQ(rx.decoder.counters().crc_errors, 0u);
  EXPECT_EQ(rx.heartbeats, 10);  // 1 Hz over 10 s
  EXPECT_EQ(rx.status_texts, 1);
  EXPECT_EQ(rx.odometry[150].time_usec,
            static_cast<uint64_t>((1000000000 + 150 * kFrameNs) / 1000));
  EXPECT_EQ(link.counters().odometry_sent, static_cast<uint64_t>(kPoses));
  EXPECT_EQ(sender.counters().drops + sender.counters().errors, 0u);
}

// A transport that decodes what it is given.
class DecodingLink : public ByteLink {
 public:
  bool send(const uint8_t* bytes, size_t n) override {
    rx.take(bytes, n);
    return true;
  }
  size_t receive(uint8_t*, size_t) override { return 0; }
  Received rx;
};

TEST(PoseLink, ALongStatusTextGoesInChunksThatJoinBackIntoIt) {
  DecodingLink wire;
  PoseLink link;
  link.init(PoseLinkConfig{}, &wire);
  const std::string reason =
      "sensor: /dev/video0: VIDIOC_DQBUF: No such device (unplugged?); reopen failed: "
      "/dev/video0: No such file or directory";  // 120 characters
  link.on_status(mavlink::kMavSeverityError, reason.c_str(), 0);
  link.on_status(mavlink::kMavSeverityInfo, "short", 0);
  link.on_status(mavlink::kMavSeverityInfo, std::string(100, 'x').c_str(), 0);
  const std::vector<mavlink::StatusText>& t = wire.rx.texts;
  ASSERT_EQ(t.size(), 3u + 1u + 3u);
  std::string joined;
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(t[i].id, t[0].id);
    EXPECT_EQ(t[i].chunk_seq, i);
    joined.append(t[i].text, strnlen(t[i].text, sizeof(t[i].text)));
  }
  EXPECT_NE(t[0].id, 0);
  EXPECT_EQ(joined, reason);
  EXPECT_EQ(t[3].id, 0) << "a text that fits is not chunked";
  EXPECT_STREQ(t[3].text, "short");
  EXPECT_NE(t[4].id, t[0].id);
  EXPECT_EQ(t[6].chunk_seq, 2);
  EXPECT_EQ(t[6].text[0], '\0') << "an empty last chunk ends a text that fills its chunks";
}

// An autopilot at the other end: what the link sends is decoded, what the autopilot says is
// received by the link.
class AutopilotLink : public ByteLink {
 public:
  bool send(const uint8_t* bytes, size_t n) override {
    sent.take(bytes, n);
    return true;
  }
  // A byte stream (serial), or one message a datagram as over UDP.
  explicit AutopilotLink(bool datagrams = false) : datagrams_(datagrams) {}
  size_t receive(uint8_t* bytes, size_t n) override {
    size_t take = n;
    if (datagrams_) {
      if (datagram_sizes_.empty()) return 0;
      take = datagram_sizes_.front();  // the rest of a datagram longer than n is lost, as in UDP
      datagram_sizes_.pop_front();
    }
    const size_t k = std::min(take, inbox_.size());
    std::copy(inbox_.begin(), inbox_.begin() + static_cast<long>(std::min(k, n)), bytes);
    inbox_.erase(inbox_.begin(), inbox_.begin() + static_cast<long>(k));
    return std::min(k, n);
  }
  template <typename Message>
  void says(const Message& m) {
    uint8_t frame[mavlink::kMaxFrameBytes];
    const int n = autopilot_.encode(m, frame);
    if (datagrams_) datagram_sizes_.push_back(static_cast<size_t>(n));
    inbox_.insert(inbox_.end(), frame, frame + n);
  }
  size_t waiting() const { return datagrams_ ? datagram_sizes_.size() : inbox_.size(); }
  Received sent;

 private:
  bool datagrams_;
  std::deque<size_t> datagram_sizes_;  // of each waiting datagram, oldest first
  mavlink::Encoder autopilot_{1, 1};   // PX4's system 1, autopilot component
  std::vector<uint8_t> inbox_;
};

TEST(PoseLink, TheLinkListensHeartbeatAndTimesync) {
  AutopilotLink wire;
  PoseLink link;
  link.init(PoseLinkConfig{}, &wire);
  // The camera's clock (ODOMETRY time_usec) runs 100 s ahead of the link's.
  constexpr int64_t kSensorAhead = 100'000'000'000;
  link.set_time_base(1'000'000'000 + kSensorAhead, 1'000'000'000);
  mavlink::Heartbeat px4;
  px4.autopilot = 12;  // MAV_AUTOPILOT_PX4
  px4.type = 2;        // quadrotor
  wire.says(px4);
  link.tick(2'000'000'000, mavlink::kMavStateActive);
  const PeerState& peer = link.peer();
  ASSERT_TRUE(peer.heard);
  EXPECT_EQ(peer.autopilot, 12);
  EXPECT_EQ(peer.system_id, 1);
  // Its request is answered at once, in the clock of time_usec.
  mavlink::Timesync request;
  request.ts1 = 777;
  wire.says(request);
  link.tick(2'010'000'000, mavlink::kMavStateActive);
  ASSERT_EQ(wire.sent.timesync.size(), 2u) << "our request, then our answer";
  const mavlink::Timesync& ours = wire.sent.timesync[0];
  const mavlink::Timesync& answer = wire.sent.timesync[1];
  EXPECT_EQ(ours.tc1, 0);
  EXPECT_EQ(ours.ts1, 2'000'000'000 + kSensorAhead);
  EXPECT_EQ(answer.tc1, 2'010'000'000 + kSensorAhead);
  EXPECT_EQ(answer.ts1, 777);
  EXPECT_EQ(answer.target_system, 1);
  EXPECT_EQ(peer.timesync_answered, 1u);
  // Its answer to ours, 20 ms later, from a clock 2 s ahead of time_usec's.
  mavlink::Timesync reply;
  reply.ts1 = ours.ts1;
  reply.tc1 = ours.ts1 + 10'000'000 + 2'000'000'000;
  wire.says(reply);
  link.tick(2'020'000'000, mavlink::kMavStateActive);
  EXPECT_EQ(peer.timesync_replies, 1u);
  EXPECT_EQ(peer.clock_offset_ns, 2'000'000'000);
  EXPECT_EQ(peer.best_round_trip_ns, 20'000'000);
  // Three seconds without a heartbeat: silent, once.
  link.tick(5'500'000'000, mavlink::kMavStateActive);
  link.tick(6'000'000'000, mavlink::kMavStateActive);
  EXPECT_TRUE(peer.silent);
  EXPECT_EQ(peer.silences, 1u);
  wire.says(px4);
  link.tick(6'100'000'000, mavlink::kMavStateActive);
  EXPECT_FALSE(peer.silent);
  EXPECT_EQ(peer.heartbeats, 2u);
}

// The autopilot heard and its clock measured, as TheLinkListensHeartbeatAndTimesync: our
// time_usec clock is 100 s ahead of the link's, the autopilot's 2 s ahead of time_usec's.
constexpr int64_t kSensorAhead = 100'000'000'000, kAutopilotAhead = 2'000'000'000;
void start_clocks(PoseLink* link) {
  link->set_time_base(1'000'000'000 + kSensorAhead, 1'000'000'000);
}
// Its answer to our latest TIMESYNC, 2 ms after we sent it, from a clock ahead_ns ahead of ours.
void answer_timesync(AutopilotLink* wire, PoseLink* link, int64_t ahead_ns) {
  mavlink::Timesync reply;
  reply.ts1 = wire->sent.timesync.back().ts1;
  reply.tc1 = reply.ts1 + 1'000'000 + ahead_ns;
  wire->says(reply);
  link->tick(reply.ts1 - kSensorAhead + 2'000'000, mavlink::kMavStateActive);
}

// The autopilot's heartbeat at now_ns, then its answer to our TIMESYNC request 2 ms after we
// sent it.
void hear_and_sync(AutopilotLink* wire, PoseLink* link, int64_t now_ns) {
  wire->says(mavlink::Heartbeat{});
  link->tick(now_ns, mavlink::kMavStateActive);
  ASSERT_FALSE(wire->sent.timesync.empty());
  answer_timesync(wire, link, kAutopilotAhead);
  ASSERT_EQ(link->peer().clock_offset_ns, kAutopilotAhead);
}

TEST(PoseLink, AClockThatDriftsIsSmoothedOneThatJumpsIsTakenAtOnce) {
  AutopilotLink wire;
  PoseLink link;
  link.init(PoseLinkConfig{}, &wire);
  start_clocks(&link);
  hear_and_sync(&wire, &link, 2'000'000'000);
  const PeerState& peer = link.peer();
  // 10 ms of drift (or of a slower path) moves the estimate a fifth of the way.
  link.tick(3'100'000'000, mavlink::kMavStateActive);
  answer_timesync(&wire, &link, kAutopilotAhead + 10'000'000);
  EXPECT_EQ(peer.clock_offset_ns, kAutopilotAhead + 2'000'000);
  EXPECT_EQ(peer.clock_jumps, 0u);
  // The autopilot rebooted: its clock restarted, 90 s behind where it was. Taken at once, so
  // that its attitudes are stamped right from the first answer.
  constexpr int64_t kRebooted = kAutopilotAhead - 90'000'000'000;
  link.tick(4'200'000'000, mavlink::kMavStateActive);
  answer_timesync(&wire, &link, kRebooted);
  EXPECT_EQ(peer.clock_offset_ns, kRebooted);
  EXPECT_EQ(peer.clock_jumps, 1u);
  EXPECT_EQ(peer.timesync_replies, 3u);
}

// Its answer to our latest TIMESYNC, round_trip_ns after we sent it, from a clock ahead_ns ahead.
void answer_after(AutopilotLink* wire, PoseLink* link, int64_t round_trip_ns, int64_t ahead_ns) {
  mavlink::Timesync reply;
  reply.ts1 = wire->sent.timesync.back().ts1;
  reply.tc1 = reply.ts1 + round_trip_ns / 2 + ahead_ns;
  wire->says(reply);
  link->tick(reply.ts1 - kSensorAhead + round_trip_ns, mavlink::kMavStateActive);
}

TEST(PoseLink, ASlowerPathBecomesTheNormAndEveryJumpOfTheClockIsCounted) {
  AutopilotLink wire;
  PoseLink link;
  link.init(PoseLinkConfig{}, &wire);
  start_clocks(&link);
  hear_and_sync(&wire, &link, 2'000'000'000);  // one quick answer: 2 ms
  const PeerState& peer = link.peer();
  // The host is loaded from now on: every answer takes 20 ms, and the autopilot's clock is 3 ms
  // further ahead. Once the quick answer is older than the last 8, the slower path is the norm.
  int64_t now_ns = 2'000'000'000;
  for (int i = 0; i < 10; ++i) {
    now_ns += 1'100'000'000;
    wire.says(mavlink::Heartbeat{});
    link.tick(now_ns, mavlink::kMavStateActive);
    answer_after(&wire, &link, 20'000'000, kAutopilotAhead + 3'000'000);
  }
  EXPECT_EQ(peer.timesync_delayed, 7u) << "while the 2 ms answer is among the last 8";
  EXPECT_EQ(peer.timesync_replies, 1u + 3u);
  EXPECT_EQ(peer.best_round_trip_ns, 20'000'000);
  EXPECT_GT(peer.clock_offset_ns, kAutopilotAhead + 1'000'000) << "following the slower answers";
  // Its clock set back and forth by 5 s at every answer: each is a jump, taken and counted.
  for (int i = 0; i < 6; ++i) {
    now_ns += 1'100'000'000;
    wire.says(mavlink::Heartbeat{});
    link.tick(now_ns, mavlink::kMavStateActive);
    const int64_t set = i % 2 == 0 ? 5'000'000'000 : 0;
    answer_after(&wire, &link, 20'000'000, kAutopilotAhead + set);
    EXPECT_EQ(peer.clock_offset_ns, kAutopilotAhead + set) << "answer " << i;
  }
  EXPECT_EQ(peer.clock_jumps, 6u);
}

// An autopilot streaming 10 000 of its own valid messages a second over UDP, one a datagram,
// while the link ticks at 30 Hz: every one is read and accounted for, and its heartbeat is heard.
TEST(PoseLink, AFloodOfTheAutopilotsMessagesIsReadAndItsHeartbeatHeard) {
  AutopilotLink wire(true);
  PoseLink link;
  link.init(PoseLinkConfig{}, &wire);
  SpscRing<AttitudeSample> attitudes;
  attitudes.allocate(64);
  link.send_attitudes_to(&attitudes);
  start_clocks(&link);
  hear_and_sync(&wire, &link, 2'000'000'000);
  constexpr int kTicks = 30 * 6, kPerTick = 10'000 / 30;
  mavlink::AttitudeQuaternion a;
  a.q[0] = 1.f;
  for (int i = 0; i < kTicks; ++i) {
    if (i % 30 == 0) wire.says(mavlink::Heartbeat{});
    for (int k = 0; k < kPerTick; ++k) wire.says(a);
    link.tick(2'010'000'000 + int64_t{i} * 33'333'333, mavlink::kMavStateActive);
    while (attitudes.front() != nullptr) attitudes.pop();  // the tracker takes its samples
  }
  const PeerState& peer = link.peer();
  const PoseLinkCounters& c = link.counters();
  EXPECT_EQ(wire.waiting(), 0u) << "nothing left unread";
  EXPECT_FALSE(peer.silent);
  EXPECT_EQ(peer.silences, 0u);
  EXPECT_EQ(peer.heartbeats, 1u + kTicks / 30);
  EXPECT_EQ(c.attitudes + c.attitudes_unsynced + c.attitudes_dropped,
            static_cast<uint64_t>(kTicks) * kPerTick)
      << "each one handed on, early or dropped at the full queue: counted once";
}

TEST(PoseLink, TheAutopilotsAttitudeReachesTheTrackerInTheSensorsClockAndItsOriginIsSent) {
  AutopilotLink wire;
  PoseLinkConfig config;
  config.send_origin = true;
  config.origin_latitude_e7 = 473977420;
  config.origin_longitude_e7 = 85455940;
  config.origin_altitude_mm = 488000;
  PoseLink link;
  link.init(config, &wire);
  start_clocks(&link);
  SpscRing<AttitudeSample> ring;
  ring.allocate(4);
  link.send_attitudes_to(&ring);
  // Before its clock is known an attitude cannot be placed in time: counted, not passed on.
  mavlink::AttitudeQuaternion early;
  early.time_boot_ms = 1000;
  wire.says(mavlink::Heartbeat{});
  wire.says(early);
  link.tick(1'500'000'000, mavlink::kMavStateActive);
  EXPECT_EQ(link.counters().attitudes_unsynced, 1u);
  EXPECT_EQ(ring.front(), nullptr);
  ASSERT_EQ(wire.sent.origins.size(), 1u) << "once, when the autopilot is first heard";
  EXPECT_EQ(wire.sent.origins[0].latitude, 473977420);
  EXPECT_EQ(wire.sent.origins[0].altitude, 488000);
  EXPECT_EQ(wire.sent.origins[0].target_system, 1);
  hear_and_sync(&wire, &link, 1'600'000'000);

  mavlink::AttitudeQuaternion a;
  a.time_boot_ms = 104'000;  // the autopilot's 104 s is our sensor's 102 s
  const Eigen::Quaterniond pitched(Eigen::AngleAxisd(0.2, Vector3d::UnitY()));
  a.q[0] = static_cast<float>(pitched.w());
  a.q[2] = static_cast<float>(pitched.y());
  a.yawspeed = 1.0f;
  wire.says(a);
  mavlink::Attitude e;  // the same, as Euler angles, 10 ms later
  e.time_boot_ms = 104'010;
  e.pitch = 0.2f;
  e.yawspeed = 1.0f;
  wire.says(e);
  link.tick(2'100'000'000, mavlink::kMavStateActive);
  EXPECT_EQ(link.counters().attitudes, 2u);
  for (int64_t t_ns : {102'000'000'000, 102'010'000'000}) {
    const AttitudeSample* s = ring.front();
    ASSERT_NE(s, nullptr);
    EXPECT_EQ(s->t_ns, t_ns);
    EXPECT_NEAR(angle_between(s->q_n_b, pitched), 0, 1e-6);
    EXPECT_FLOAT_EQ(static_cast<float>(s->rate_b_rad_s.z()), 1.0f);
    EXPECT_NEAR(s->timing_sigma_s, 0.5 * 0.002 + 0.0005, 1e-12) << "half the round trip, and ms";
    ring.pop();
  }
  // A full queue drops and counts, never blocks.
  for (int i = 0; i < 6; ++i) {
    a.time_boot_ms = 105'000 + static_cast<uint32_t>(i) * 10;
    wire.says(a);
  }
  link.tick(2'200'000'000, mavlink::kMavStateActive);
  EXPECT_EQ(link.counters().attitudes_dropped, 2u);
  // Back after a silence (it may have rebooted): told its origin again.
  link.tick(6'000'000'000, mavlink::kMavStateActive);
  ASSERT_TRUE(link.peer().silent);
  wire.says(mavlink::Heartbeat{});
  link.tick(6'100'000'000, mavlink::kMavStateActive);
  EXPECT_EQ(wire.sent.origins.size(), 2u);
  EXPECT_EQ(link.counters().origins_sent, 2u);
}

TEST(PoseLink, StampsInTheAutopilotsClockWaitForTimesync) {
  AutopilotLink wire;
  PoseLinkConfig config;
  config.time_in_autopilot_clock = true;
  PoseLink link;
  link.init(config, &wire);
  start_clocks(&link);
  PoseEstimate p = pose_at(0, Vector3d::Zero());
  p.timestamp_ns = 1'000'000'000 + kSensorAhead;
  link.on_pose(p, 1'000'000'000);
  EXPECT_EQ(link.counters().held_unsynced, 1u) << "no time_usec in a clock not yet known";
  EXPECT_TRUE(wire.sent.odometry.empty());
  hear_and_sync(&wire, &link, 2'000'000'000);
  link.on_pose(p, 2'100'000'000);
  ASSERT_EQ(wire.sent.odometry.size(), 1u);
  EXPECT_EQ(wire.sent.odometry[0].time_usec,
            static_cast<uint64_t>((p.timestamp_ns + kAutopilotAhead) / 1000));
}

TEST(PoseLink, ALevelFrameTurnsOdometryAndMovesTheResetCounterOn) {
  PoseLinkConfig config;
  config.T_b_c = body_from_camera();
  PoseLink link;
  link.init(config, nullptr);
  // The body pitched up 0.2 rad at the world's origin: unlevelled, ODOMETRY says no turn.
  const PoseEstimate p = pose_at(0, Vector3d::Zero());
  const mavlink::Odometry before = link.odometry_of(p);
  EXPECT_NEAR(before.q[0], 1.0, 1e-6);
  const Eigen::Quaterniond pitched(Eigen::AngleAxisd(0.2, Vector3d::UnitY()));
  link.set_level(level_from_world(down_in_world(pitched, config.T_b_c, p.T_w_c), config.T_b_c));
  const mavlink::Odometry after = link.odometry_of(p);
  EXPECT_NEAR(after.x, 0, 1e-6) << "the body at the world's origin stays at the frame's origin";
  const Eigen::Quaterniond q(after.q[0], after.q[1], after.q[2], after.q[3]);
  EXPECT_NEAR(angle_between(q, pitched), 0, 1e-6) << "the body's pitch, now seen";
  EXPECT_EQ(after.reset_counter, before.reset_counter + 1) << "the frame changed under the EKF";
  link.set_level(level_from_world(down_in_world(pitched, config.T_b_c, p.T_w_c), config.T_b_c));
  EXPECT_EQ(link.odometry_of(p).reset_counter, after.reset_counter) << "the same frame again";
}

// Two of docs/firmware.md's mountings: a camera moved along its image's "up" is, looking down
// with the image's top to the front, the body moving forward; looking forward, moving along its
// optical axis is.
TEST(PoseLink, TheReadmesMountingsPutTheBodysForwardWhereTheySay) {
  const double h = std::sqrt(0.5);
  for (const auto& [q_b_c, camera_forward] :
       {std::make_pair(Eigen::Quaterniond(0.5, 0.5, 0.5, 0.5), Vector3d(0, 0, 1)),
        std::make_pair(Eigen::Quaterniond(h, 0, 0, h), Vector3d(0, -1, 0))}) {
    PoseLinkConfig config;
    config.T_b_c = SE3(q_b_c, Vector3d::Zero());
    PoseLink link;
    link.init(config, nullptr);
    const mavlink::Odometry o = link.odometry_of(pose_at(30, camera_forward));  // 1 m/s for 1 s
    EXPECT_NEAR(o.x, 1.0, 1e-5);
    EXPECT_NEAR(o.y, 0.0, 1e-5);
    EXPECT_NEAR(o.z, 0.0, 1e-5);
  }
}

// Before the first frame the link has no sensor clock to speak in: it neither asks nor answers
// TIMESYNC (a measurement begun then would mix two clocks). A sensor reopened in another clock
// makes the autopilot's clock unknown until it is measured again.
TEST(PoseLink, TimesyncWaitsForTheFirstFrameAndStartsAgainWhenTheSensorsClockJumps) {
  AutopilotLink wire;
  PoseLink link;
  link.init(PoseLinkConfig{}, &wire);
  wire.says(mavlink::Heartbeat{});
  mavlink::Timesync request;
  request.ts1 = 777;
  wire.says(request);
  link.tick(1'000'000'000, mavlink::kMavStateStandby);
  EXPECT_TRUE(link.peer().heard);
  EXPECT_TRUE(wire.sent.timesync.empty()) << "no request and no answer without a sensor clock";
  start_clocks(&link);
  hear_and_sync(&wire, &link, 1'200'000'000);
  EXPECT_TRUE(link.peer().clock_known);
  link.set_time_base(5'000'000'000, 1'300'000'000);  // the sensor's clock restarted
  EXPECT_FALSE(link.peer().clock_known);
  link.set_time_base(5'000'000'100, 1'300'000'000);  // a frame's arrival jitter is no jump
  EXPECT_FALSE(link.peer().clock_known);
}

TEST(PoseLink, TheLatencyGoesOutAsThreeNamedValues) {
  AutopilotLink wire;
  PoseLink link;
  link.init(PoseLinkConfig{}, &wire);
  link.on_latency(4.5f, 7.75f, 12.0f, 3'000'000'000);
  ASSERT_EQ(wire.sent.values.size(), 3u);
  const char* names[] = {"lat_med_ms", "lat_p95_ms", "lat_max_ms"};
  const float values[] = {4.5f, 7.75f, 12.0f};
  for (int i = 0; i < 3; ++i) {
    const mavlink::NamedValueFloat& v = wire.sent.values[static_cast<size_t>(i)];
    EXPECT_EQ(std::string(v.name, strnlen(v.name, sizeof(v.name))), names[i]);
    EXPECT_EQ(v.value, values[i]);
    EXPECT_EQ(v.time_boot_ms, 3000u);
  }
  EXPECT_EQ(link.counters().latency_reports, 1u);
}

// A pseudo-terminal pair: the link writes the slave as it would a UART; the test reads the
// master. The pty does not pace bytes by baud: the link's own rate policy does.
class PtyPair {
 public:
  PtyPair() {
    char name[128];
    ok_ = ::openpty(&master_, &slave_, name, nullptr, nullptr) == 0;
    if (ok_) {
      slave_name_ = name;
      ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
    }
  }
  ~PtyPair() {
    if (ok_) {
      ::close(master_);
      ::close(slave_);
    }
  }
  bool ok() const { return ok_; }
  const char* slave_name() const { return slave_name_.c_str(); }
  size_t read(uint8_t* buf, size_t n) {
    const ssize_t got = ::read(master_, buf, n);
    return got > 0 ? static_cast<size_t>(got) : 0;
  }

 private:
  bool ok_ = false;
  int master_ = -1, slave_ = -1;
  std::string slave_name_;
};

struct SerialRun {
  PoseLinkCounters link;
  LinkCounters transport;
  size_t received = 0;
  uint64_t crc_errors = 0;
};

SerialRun stream_over_pty(uint32_t baud, int64_t period_ns, int poses) {
  SerialRun out;
  PtyPair pty;
  EXPECT_TRUE(pty.ok());
  SerialLink serial;
  EXPECT_TRUE(serial.open(pty.slave_name(), baud).is_ok());
  PoseLink link;
  link.init(PoseLinkConfig{}, &serial);
  Received rx;
  uint8_t buf[4096];
  for (int i = 0; i < poses; ++i) {
    const int64_t now = i * period_ns;
    link.tick(now, mavlink::kMavStateActive);
    link.on_pose(pose_at(i, Vector3d(0.1, 0, 0)), now);
    for (size_t n; (n = pty.read(buf, sizeof(buf))) > 0;) rx.take(buf, n);
  }
  for (int spin = 0; spin < 100 && serial.flush() > 0; ++spin) {
    for (size_t n; (n = pty.read(buf, sizeof(buf))) > 0;) rx.take(buf, n);
  }
  for (size_t n; (n = pty.read(buf, sizeof(buf))) > 0;) rx.take(buf, n);
  out.link = link.counters();
  out.transport = serial.counters();
  out.received = rx.odometry.size();
  out.crc_errors = rx.decoder.counters().crc_errors;
  return out;
}

TEST(PoseLink, SerialAt921600CarriesEveryPoseAt30Hz) {
  const SerialRun r = stream_over_pty(921600, kFrameNs, 150);
  EXPECT_EQ(r.received, 150u);
  EXPECT_EQ(r.link.odometry_rate_limited, 0u);
  EXPECT_EQ(r.crc_errors, 0u);
}

TEST(PoseLink, SerialAt115200CarriesThirtyHertzAndThinsSixtyHertzToTheLineRate) {
  // 245-byte frames: 30 Hz needs 7350 B/s of the 11520 the line carries.
  const SerialRun at30 = stream_over_pty(115200, kFrameNs, 150);
  EXPECT_EQ(at30.received, 150u);
  EXPECT_EQ(at30.link.odometry_rate_limited, 0u);
  // 60 Hz needs 14700 B/s: poses are skipped, never queued, and what goes out fits the line.
  constexpr int kPoses = 600;  // 10 s
  const SerialRun at60 = stream_over_pty(115200, kFrameNs / 2, kPoses);
  const double line_bytes = 11520.0 * 10.0 + 11520.0 * 0.1;  // 10 s plus the burst
  EXPECT_GT(at60.link.odometry_rate_limited, 0u);
  EXPECT_LE(static_cast<double>(at60.transport.tx_bytes), line_bytes + 2 * 245);
  EXPECT_GE(static_cast<double>(at60.received), 0.95 * 11520.0 * 10.0 / 245.0 - 20);
  EXPECT_EQ(at60.received, at60.link.odometry_sent);
  EXPECT_EQ(at60.crc_errors, 0u);
  std::printf("115200 baud, 60 Hz for 10 s: %zu of %d poses sent, %llu skipped, %llu bytes\n",
              at60.received, kPoses,
              static_cast<unsigned long long>(at60.link.odometry_rate_limited),
              static_cast<unsigned long long>(at60.transport.tx_bytes));
}

TEST(PoseLink, AFullSerialPortRefusesFramesInsteadOfBlocking) {
  PtyPair pty;  // nobody reads the master: the pty and then the ring fill up
  ASSERT_TRUE(pty.ok());
  SerialLink serial;
  ASSERT_TRUE(serial.open(pty.slave_name(), 921600).is_ok());
  const uint8_t frame[245] = {0xFD};
  int refused = 0;
  for (int i = 0; i < 2000; ++i) refused += serial.send(frame, sizeof(frame)) ? 0 : 1;
  EXPECT_GT(refused, 0);  // returned: had send blocked, this test would never get here
  EXPECT_EQ(serial.counters().drops, static_cast<uint64_t>(refused));
  EXPECT_EQ(serial.counters().errors, 0u);
}

TEST(PoseLink, BadTransportSettingsAreErrorsNotCrashes) {
  SerialLink serial;
  const Status baud = serial.open("/dev/null", 123456);
  EXPECT_FALSE(baud.is_ok());
  EXPECT_NE(std::string(baud.message()).find("123456"), std::string::npos);
  SerialLink missing;
  EXPECT_FALSE(missing.open("/nonexistent/tty", 115200).is_ok());
  SerialLink not_a_tty;
  EXPECT_FALSE(not_a_tty.open("/dev/null", 115200).is_ok());
  UdpLink udp;
  EXPECT_FALSE(udp.open("localhost", 14550, 0).is_ok());  // numeric addresses only
}

TEST(PoseLink, UdpBroadcastIsAllowed) {
  // Without SO_BROADCAST every frame to 255.255.255.255 failed with EACCES, unreported.
  UdpLink udp;
  ASSERT_TRUE(udp.open("255.255.255.255", 14599, 0).is_ok());
  const uint8_t frame[8] = {0xfd};
  udp.send(frame, sizeof(frame));
  EXPECT_NE(udp.counters().last_error, EACCES);
}

TEST(PoseLink, ASerialPortWhoseReaderLeftCountsWhatWasLostAndWhy) {
  int master = -1, slave = -1;
  ASSERT_EQ(::openpty(&master, &slave, nullptr, nullptr, nullptr), 0);
  char name[64];
  ASSERT_EQ(::ttyname_r(slave, name, sizeof(name)), 0);
  SerialLink serial;
  ASSERT_TRUE(serial.open(name, 115200).is_ok());
  ::close(slave);
  ::close(master);  // the reader is gone: writes fail with EIO
  const uint8_t frame[64] = {0xfd};
  for (int i = 0; i < 3; ++i) serial.send(frame, sizeof(frame));
  serial.flush();
  EXPECT_GT(serial.counters().errors, 0u);
  EXPECT_EQ(serial.counters().last_error, EIO);
  EXPECT_GT(serial.counters().lost_bytes, 0u);
}

}  // namespace
}  // namespace rgbdtam

#pragma once
// The pose link task: turns each PoseEstimate into a MAVLink ODOMETRY for the robot's
// controller, sends HEARTBEAT at 1 Hz and STATUSTEXT for events, over any ByteLink.
//
// Frames: the local frame is the body frame at the first tracked frame (MAV_FRAME_LOCAL_FRD
// when the body is front-right-down), the child frame is the body (MAV_FRAME_BODY_FRD); the
// body-from-camera extrinsics T_b_c come from the board file.
//
// Rate policy: the link never queues more than the line carries. A token bucket filled at
// the transport's line rate (bytes/s; unlimited for UDP) decides whether an ODOMETRY goes
// out; when it cannot, that pose is skipped and counted, and the next (newer) one is offered.
// HEARTBEAT and STATUSTEXT always go first. At 115200 baud a 245-byte ODOMETRY at 30 Hz
// takes 64 % of the line and is never skipped; at 60 Hz, or at 57600 baud, poses are thinned.

#include <cstdint>

#include "rgbdtam/core/attitude.hpp"
#include "rgbdtam/core/se3.hpp"
#include "rgbdtam/port/byte_link.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/port/spsc_ring.hpp"
#include "rgbdtam/runtime/mavlink.hpp"

namespace rgbdtam {

struct PoseLinkConfig {
  uint8_t system_id = 1;
  uint8_t component_id = 197;  // MAV_COMP_ID_VISUAL_INERTIAL_ODOMETRY
  SE3 T_b_c;                   // body from camera
  uint8_t frame_id = mavlink::kMavFrameLocalFrd;
  uint8_t child_frame_id = mavlink::kMavFrameBodyFrd;
  int64_t heartbeat_period_ns = 1000000000;
  int64_t burst_ns = 100000000;  // the token bucket holds this much line time
  // Stamp ODOMETRY and OBSTACLE_DISTANCE in the autopilot's clock (capture time moved by the
  // TIMESYNC offset); until TIMESYNC has an answer they are held back, not sent in another clock.
  bool time_in_autopilot_clock = false;
  // Sent as SET_GPS_GLOBAL_ORIGIN each time the autopilot is heard (again), when set.
  bool send_origin = false;
  int32_t origin_latitude_e7 = 0, origin_longitude_e7 = 0, origin_altitude_mm = 0;
};

struct PoseLinkCounters {
  uint64_t odometry_sent = 0;
  uint64_t odometry_rate_limited = 0;  // skipped by the rate policy
  uint64_t odometry_refused = 0;       // refused by the transport (its drops/errors)
  uint64_t heartbeats_sent = 0;
  uint64_t status_texts_sent = 0;
  uint64_t obstacles_sent = 0;  // OBSTACLE_DISTANCE, skipped and refused as ODOMETRY is
  uint64_t obstacles_rate_limited = 0;
  uint64_t obstacles_refused = 0;
  uint64_t held_unsynced = 0;  // not sent: time_in_autopilot_clock before TIMESYNC answered
  uint64_t origins_sent = 0;
  uint64_t latency_reports = 0;     // sets of the three NAMED_VALUE_FLOAT
  uint64_t attitudes = 0;           // ATTITUDE(_QUATERNION) from the autopilot handed on
  uint64_t attitudes_unsynced = 0;  // ... not: its clock not yet known
  uint64_t attitudes_dropped = 0;   // ... not: the tracker's queue was full
  uint32_t frame_changes = 0;       // level frame found or changed: reset_counter moved on
};

// What the link has heard from the other MAVLink system on it (the autopilot).
struct PeerState {
  bool heard = false;  // a HEARTBEAT from another system
  uint8_t system_id = 0, component_id = 0, autopilot = 0, type = 0;
  int64_t last_heartbeat_ns = -1;
  uint32_t heartbeats = 0;
  bool silent = false;             // no HEARTBEAT for PoseLink::kPeerSilentNs
  uint32_t silences = 0;           // times it went silent
  uint32_t timesync_answered = 0;  // its TIMESYNC requests we answered
  uint32_t timesync_requests = 0;  // ours to it
  uint32_t timesync_replies = 0;   // its answers to ours
  uint32_t clock_jumps = 0;        // answers that moved its clock more than a second (a reboot)
  // Its clock minus the clock of our ODOMETRY time_usec, ns, from round trips no longer than
  // twice the shortest of the last PoseLink::kRoundTrips (a busier path becomes the norm);
  // valid once an answer was taken (again after our clock jumped).
  bool clock_known = false;
  int64_t clock_offset_ns = 0;
  int64_t best_round_trip_ns = -1;
  uint32_t timesync_delayed = 0;  // answers not used: their round trip was too long
  uint64_t frames = 0;            // good frames received
};

// The receiving side's inverse of PoseLink's frames: the camera pose T_w_c (world = the first
// camera) an ODOMETRY describes, given the same body-from-camera extrinsics.
SE3 camera_pose_of(const mavlink::Odometry& o, const SE3& T_b_c);

class PoseLink {
 public:
  void init(const PoseLinkConfig& config, ByteLink* link);
  // One tracked frame (valid or not: a lost frame is reported with quality -1).
  void on_pose(const PoseEstimate& pose, int64_t now_ns);
  // Obstacle sectors measured on the depth frame stamped timestamp_ns (sensor clock), as
  // OBSTACLE_DISTANCE in the body frame.
  void on_obstacles(const ObstacleSectors& sectors, int64_t timestamp_ns, int64_t now_ns);
  // The latency from a frame's arrival to its ODOMETRY so far, ms, as three NAMED_VALUE_FLOAT a
  // ground station plots: lat_med_ms, lat_p95_ms, lat_max_ms.
  void on_latency(float median_ms, float p95_ms, float max_ms, int64_t now_ns);
  // An event for the operator (text is cut to 50 characters).
  void on_status(uint8_t severity, const char* text, int64_t now_ns);
  // Heartbeat and TIMESYNC requests when due, what the autopilot sent, and transport flushing;
  // call at least every frame period.
  void tick(int64_t now_ns, uint8_t system_status);
  // Relates the clock of ODOMETRY time_usec (the sensor's stamps) to now_ns's: a frame stamped
  // sensor_ns arrived at arrival_ns. TIMESYNC is answered and asked in the sensor's clock, so
  // not before the first frame; a jump of that clock (a sensor reopened) measures the
  // autopilot's clock afresh.
  void set_time_base(int64_t sensor_ns, int64_t arrival_ns);
  const PoseLinkCounters& counters() const { return counters_; }
  const PeerState& peer() const { return peer_; }
  static constexpr int64_t kPeerSilentNs = 3'000'000'000;  // three missed 1 Hz heartbeats

  // The ODOMETRY a pose becomes (exposed for tests).
  mavlink::Odometry odometry_of(const PoseEstimate& pose);
  // The level frame (gravity down) from the world, which ODOMETRY's frame becomes; until then it
  // is the body at the world's origin. A change after poses went out in the old frame is a
  // reset (reset_counter moves on).
  void set_level(const Eigen::Quaterniond& q_l_w);
  // Init time: the autopilot's attitudes go here, in the sensor's clock, for the tracker.
  void send_attitudes_to(SpscRing<AttitudeSample>* ring) { attitudes_ = ring; }

 private:
  bool spend(int n, int64_t now_ns, bool must, int keep = 0);
  // time_usec for a stamp in the sensor's clock; false when it cannot be given yet.
  bool stamp_usec(int64_t sensor_ns, uint64_t* usec) const;
  SE3 T_l_w() const;  // the ODOMETRY frame from the world
  void on_attitude(const mavlink::AttitudeQuaternion& a);
  void on_attitude(const mavlink::Attitude& e);
  void on_heartbeat(const mavlink::Frame& f, int64_t now_ns);
  void on_timesync(const mavlink::Frame& f, int64_t now_ns);
  void on_clock_offset(int64_t offset_ns, int64_t round_trip_ns);
  void listen(int64_t now_ns);
  void on_frame(const mavlink::Frame& f, int64_t now_ns);
  // A message that must go out (status, heartbeat, TIMESYNC): spent past the rate policy.
  template <typename Message>
  bool send_now(const Message& m, int64_t now_ns);
  // A message the rate policy may skip (ODOMETRY, OBSTACLE_DISTANCE), counted in one of three;
  // sent only if `keep` bytes of line time are left after it.
  template <typename Message>
  void send_if_room(const Message& m, int64_t now_ns, uint64_t* sent, uint64_t* rate_limited,
                    uint64_t* refused, int keep = 0);

  PoseLinkConfig config_;
  ByteLink* link_ = nullptr;
  mavlink::Encoder encoder_{1, 197};
  uint16_t next_text_id_ = 0;  // of a chunked text; 0 means "not chunked"
  mavlink::Decoder decoder_;
  PeerState peer_;
  int64_t sensor_minus_now_ns_ = 0;
  bool time_base_set_ = false;
  // The last round trips, newest at round_trip_next_ - 1.
  static constexpr int kRoundTrips = 8;
  int64_t round_trips_[kRoundTrips] = {};
  int round_trip_count_ = 0, round_trip_next_ = 0;
  int64_t timesync_sent_ns_ = -1;  // now_ns of our pending request
  int64_t timesync_sent_ts1_ = 0;  // its ts1, in the sensor's clock
  int64_t last_heartbeat_ns_ = -1;
  int64_t last_timesync_ns_ = -1;  // our last request
  double tokens_ = 0;
  int64_t tokens_at_ns_ = -1;
  // The previous valid body pose, for velocities.
  bool have_previous_ = false;
  SE3 T_l_b_previous_;
  int64_t previous_ns_ = 0;
  uint32_t previous_reset_ = 0;
  bool levelled_ = false;
  Eigen::Quaterniond q_l_w_ = Eigen::Quaterniond::Identity();
  bool valid_sent_in_frame_ = false;  // a valid ODOMETRY went out in the current frame
  SpscRing<AttitudeSample>* attitudes_ = nullptr;
  PoseLinkCounters counters_;
};

}  // namespace rgbdtam

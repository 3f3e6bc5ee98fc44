#include "rgbdtam/runtime/pose_link.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

namespace rgbdtam {

SE3 camera_pose_of(const mavlink::Odometry& o, const SE3& T_b_c) {
  const SE3 T_l_b(Eigen::Quaterniond(o.q[0], o.q[1], o.q[2], o.q[3]), Vector3d(o.x, o.y, o.z));
  return T_b_c.inverse() * T_l_b * T_b_c;
}

void PoseLink::init(const PoseLinkConfig& config, ByteLink* link) {
  config_ = config;
  link_ = link;
  encoder_ = mavlink::Encoder(config.system_id, config.component_id);
}

// A clock that moved further than this between two measurements jumped (was set, or restarted):
// no round trip that passes the filter is that long.
constexpr int64_t kClockJumpNs = 1'000'000'000;

void PoseLink::set_time_base(int64_t sensor_ns, int64_t arrival_ns) {
  const int64_t base = sensor_ns - arrival_ns;
  if (time_base_set_ && std::llabs(base - sensor_minus_now_ns_) > kClockJumpNs) {
    peer_.clock_known = false;
    peer_.best_round_trip_ns = -1;
    round_trip_count_ = 0;
    timesync_sent_ns_ = -1;
  }
  sensor_minus_now_ns_ = base;
  time_base_set_ = true;
}

bool PoseLink::stamp_usec(int64_t sensor_ns, uint64_t* usec) const {
  int64_t t_ns = sensor_ns;
  if (config_.time_in_autopilot_clock) {
    if (!peer_.clock_known) return false;
    t_ns += peer_.clock_offset_ns;
  }
  *usec = static_cast<uint64_t>(std::max<int64_t>(0, t_ns / 1000));
  return true;
}

SE3 PoseLink::T_l_w() const {
  // Unlevelled, the local frame is the body at the world's origin: T_l_w = T_b_c. Levelled, that
  // body turned so that gravity is down, about its own origin.
  if (!levelled_) return config_.T_b_c;
  const Eigen::Quaterniond q_l_b0 = q_l_w_ * config_.T_b_c.quaternion().conjugate();
  return SE3(q_l_b0, Vector3d::Zero()) * config_.T_b_c;
}

void PoseLink::set_level(const Eigen::Quaterniond& q_l_w) {
  if (levelled_ && q_l_w_.coeffs() == q_l_w.coeffs()) return;
  if (valid_sent_in_frame_) {
    ++counters_.frame_changes;
    valid_sent_in_frame_ = false;
  }
  levelled_ = true;
  q_l_w_ = q_l_w;
  have_previous_ = false;  // no velocity across the change
}

mavlink::Odometry PoseLink::odometry_of(const PoseEstimate& pose) {
  mavlink::Odometry o;
  (void)stamp_usec(pose.timestamp_ns, &o.time_usec);
  o.frame_id = config_.frame_id;
  o.child_frame_id = config_.child_frame_id;
  const uint32_t reset_counter = pose.reset_counter + counters_.frame_changes;
  o.reset_counter = static_cast<uint8_t>(reset_counter);
  o.estimator_type = mavlink::kMavEstimatorTypeVision;
  o.velocity_covariance[0] = NAN;  // unknown
  const SE3 T_l_b = T_l_w() * pose.T_w_c * config_.T_b_c.inverse();
  // A pose that is not finite never goes out as valid, whatever flagged it.
  const bool finite = T_l_b.translation().allFinite() && T_l_b.quaternion().coeffs().allFinite();
  if ((pose.flags & kPoseValid) == 0 || !finite) {
    o.x = o.y = o.z = NAN;
    for (float& q : o.q) q = NAN;
    o.vx = o.vy = o.vz = o.rollspeed = o.pitchspeed = o.yawspeed = NAN;
    o.pose_covariance[0] = NAN;
    o.quality = -1;
    have_previous_ = false;
    return o;
  }
  o.x = static_cast<float>(T_l_b.translation().x());
  o.y = static_cast<float>(T_l_b.translation().y());
  o.z = static_cast<float>(T_l_b.translation().z());
  const Eigen::Quaterniond& q = T_l_b.quaternion();
  o.q[0] = static_cast<float>(q.w());
  o.q[1] = static_cast<float>(q.x());
  o.q[2] = static_cast<float>(q.y());
  o.q[3] = static_cast<float>(q.z());
  const double dt_s = (pose.timestamp_ns - previous_ns_) * 1e-9;
  if (have_previous_ && reset_counter == previous_reset_ && dt_s > 0) {
    const SE3 T_prev_now = T_l_b_previous_.inverse() * T_l_b;  // body motion, in the body
    const Vector3d v =
        T_l_b.rotation().transpose() * (T_l_b.translation() - T_l_b_previous_.translation()) / dt_s;
    const Vector3d w = so3_log(T_prev_now.quaternion()) / dt_s;
    o.vx = static_cast<float>(v.x());
    o.vy = static_cast<float>(v.y());
    o.vz = static_cast<float>(v.z());
    o.rollspeed = static_cast<float>(w.x());
    o.pitchspeed = static_cast<float>(w.y());
    o.yawspeed = static_cast<float>(w.z());
  } else {
    o.vx = o.vy = o.vz = o.rollspeed = o.pitchspeed = o.yawspeed = NAN;
  }
  have_previous_ = true;
  T_l_b_previous_ = T_l_b;
  previous_ns_ = pose.timestamp_ns;
  previous_reset_ = reset_counter;
  valid_sent_in_frame_ = true;
  // The Gauss-Newton information is over a camera-frame twist (v, omega); rotate both blocks
  // into the local frame. Rotation variances are small-angle, about the local axes.
  const Eigen::Matrix<double, 6, 6> cov_c = pose_covariance(pose);
  if (cov_c.allFinite()) {
    const Matrix3d R_l_c = (T_l_w() * pose.T_w_c).rotation();
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
    A.topLeftCorner<3, 3>() = R_l_c;
    A.bottomRightCorner<3, 3>() = R_l_c;
    const Eigen::Matrix<double, 6, 6> cov = A * cov_c * A.transpose();
    int k = 0;
    for (int r = 0; r < 6; ++r) {
      for (int c = r; c < 6; ++c) o.pose_covariance[k++] = static_cast<float>(cov(r, c));
    }
  } else {
    o.pose_covariance[0] = NAN;
  }
  o.quality = static_cast<int8_t>(std::clamp<long>(std::lround(100.0 * pose.overlap), 1, 100));
  return o;
}

bool PoseLink::spend(int n, int64_t now_ns, bool must, int keep) {
  const double rate = link_->line_rate_bytes_per_s();
  if (rate <= 0) return true;
  const double cap = std::max(rate * config_.burst_ns * 1e-9, 2.0 * mavlink::kMaxFrameBytes);
  if (tokens_at_ns_ < 0) tokens_ = cap;
  if (tokens_at_ns_ >= 0 && now_ns > tokens_at_ns_)
    tokens_ += rate * (now_ns - tokens_at_ns_) * 1e-9;
  tokens_ = std::min(tokens_, cap);
  tokens_at_ns_ = now_ns;
  if (tokens_ < n + keep && !must) return false;
  tokens_ -= n;
  return true;
}

template <typename Message>
void PoseLink::send_if_room(const Message& m, int64_t now_ns, uint64_t* sent,
                            uint64_t* rate_limited, uint64_t* refused, int keep) {
  uint8_t frame[mavlink::kMaxFrameBytes];
  const int n = encoder_.encode(m, frame);
  if (!spend(n, now_ns, false, keep)) {
    ++*rate_limited;
  } else if (link_->send(frame, static_cast<size_t>(n))) {
    ++*sent;
  } else {
    ++*refused;
  }
}

void PoseLink::on_pose(const PoseEstimate& pose, int64_t now_ns) {
  uint64_t usec = 0;
  if (!stamp_usec(pose.timestamp_ns, &usec)) {
    ++counters_.held_unsynced;
    return;
  }
  send_if_room(odometry_of(pose), now_ns, &counters_.odometry_sent,
               &counters_.odometry_rate_limited, &counters_.odometry_refused);
}

void PoseLink::on_obstacles(const ObstacleSectors& sectors, int64_t timestamp_ns, int64_t now_ns) {
  mavlink::ObstacleDistance m;
  if (!stamp_usec(timestamp_ns, &m.time_usec)) {
    ++counters_.held_unsynced;
    return;
  }
  std::copy(sectors.distance_cm, sectors.distance_cm + ObstacleSectors::kCount, m.distances);
  m.min_distance = sectors.min_cm;
  m.max_distance = sectors.max_cm;
  // Receivers that read only the whole-degree field get the nearest non-zero width.
  m.increment = static_cast<uint8_t>(std::max(1.0f, std::round(sectors.increment_deg)));
  m.increment_f = sectors.increment_deg;
  m.angle_offset = sectors.angle_offset_deg;
  // On a slow line the next ODOMETRY comes first: obstacles leave room for one.
  constexpr int kOdometryFrameBytes =
      mavlink::kHeaderBytes + mavlink::kOdometry.payload_bytes + mavlink::kChecksumBytes;
  send_if_room(m, now_ns, &counters_.obstacles_sent, &counters_.obstacles_rate_limited,
               &counters_.obstacles_refused, kOdometryFrameBytes);
}

template <typename Message>
bool PoseLink::send_now(const Message& m, int64_t now_ns) {
  uint8_t frame[mavlink::kMaxFrameBytes];
  const int n = encoder_.encode(m, frame);
  (void)spend(n, now_ns, true);
  return link_->send(frame, static_cast<size_t>(n));
}

void PoseLink::on_latency(float median_ms, float p95_ms, float max_ms, int64_t now_ns) {
  const std::pair<const char*, float> values[] = {
      {"lat_med_ms", median_ms}, {"lat_p95_ms", p95_ms}, {"lat_max_ms", max_ms}};
  for (const auto& [name, value] : values) {
    mavlink::NamedValueFloat m;
    m.time_boot_ms = static_cast<uint32_t>(now_ns / 1'000'000);
    m.value = value;
    // Ten characters fill the field without a NUL, as MAVLink allows.
    std::memcpy(m.name, name, std::min(sizeof(m.name), std::strlen(name)));
    (void)send_now(m, now_ns);
  }
  ++counters_.latency_reports;
}

void PoseLink::on_status(uint8_t severity, const char* text, int64_t now_ns) {
  mavlink::StatusText s;
  s.severity = severity;
  constexpr size_t kChunk = sizeof(s.text);
  const size_t length = strnlen(text, kMaxStatusTextChars);
  // A longer text goes in chunks sharing a non-zero id; the last one ends in a NUL (an empty
  // chunk when the text fills the one before), which tells the receiver it is complete.
  if (length > kChunk) {
    next_text_id_ = static_cast<uint16_t>(next_text_id_ == UINT16_MAX ? 1 : next_text_id_ + 1);
    s.id = next_text_id_;
  }
  for (size_t at = 0;; at += kChunk) {
    std::memset(s.text, 0, kChunk);
    const size_t n_chars = std::min(kChunk, length - std::min(length, at));
    std::memcpy(s.text, text + at, n_chars);
    if (send_now(s, now_ns)) ++counters_.status_texts_sent;
    if (n_chars < kChunk || s.id == 0) break;
    ++s.chunk_seq;
  }
}

void PoseLink::on_frame(const mavlink::Frame& f, int64_t now_ns) {
  if (f.system_id == config_.system_id && f.component_id == config_.component_id) return;
  ++peer_.frames;
  const bool from_peer =
      peer_.heard && f.system_id == peer_.system_id && f.component_id == peer_.component_id;
  switch (f.message_id) {
    case mavlink::kHeartbeat.id:
      on_heartbeat(f, now_ns);
      break;
    case mavlink::kAttitudeQuaternion.id:
      if (from_peer) on_attitude(mavlink::unpacked<mavlink::AttitudeQuaternion>(f));
      break;
    case mavlink::kAttitude.id:
      if (from_peer) on_attitude(mavlink::unpacked<mavlink::Attitude>(f));
      break;
    case mavlink::kTimesync.id:
      if (time_base_set_) on_timesync(f, now_ns);
      break;
    default:
      break;
  }
}

void PoseLink::on_heartbeat(const mavlink::Frame& f, int64_t now_ns) {
  const auto hb = mavlink::unpacked<mavlink::Heartbeat>(f);
  // The operator learns when the autopilot appears and when it comes back.
  const bool newly_back = peer_.heard && peer_.silent;
  if (!peer_.heard || peer_.silent) {
    char text[kMaxStatusTextChars + 1];
    std::snprintf(text, sizeof(text), "autopilot: heard, system %u component %u, MAV_AUTOPILOT %u",
                  f.system_id, f.component_id, hb.autopilot);
    on_status(mavlink::kMavSeverityInfo, text, now_ns);
  }
  peer_.heard = true;
  peer_.silent = false;
  peer_.system_id = f.system_id;
  peer_.component_id = f.component_id;
  peer_.autopilot = hb.autopilot;
  peer_.type = hb.type;
  peer_.last_heartbeat_ns = now_ns;
  ++peer_.heartbeats;
  // An autopilot heard for the first time, or again after a silence (it may have rebooted),
  // is told where its origin is, so that modes needing one work without GPS.
  if (config_.send_origin && (peer_.heartbeats == 1 || newly_back)) {
    mavlink::SetGpsGlobalOrigin origin;
    origin.latitude = config_.origin_latitude_e7;
    origin.longitude = config_.origin_longitude_e7;
    origin.altitude = config_.origin_altitude_mm;
    origin.target_system = f.system_id;
    if (send_now(origin, now_ns)) ++counters_.origins_sent;
  }
}

void PoseLink::on_attitude(const mavlink::Attitude& e) {
  const Eigen::Quaterniond q = quaternion_from_yaw_pitch_roll(e.yaw, e.pitch, e.roll);
  mavlink::AttitudeQuaternion a;
  a.time_boot_ms = e.time_boot_ms;
  a.q[0] = static_cast<float>(q.w());
  a.q[1] = static_cast<float>(q.x());
  a.q[2] = static_cast<float>(q.y());
  a.q[3] = static_cast<float>(q.z());
  a.rollspeed = e.rollspeed;
  a.pitchspeed = e.pitchspeed;
  a.yawspeed = e.yawspeed;
  on_attitude(a);
}

void PoseLink::on_timesync(const mavlink::Frame& f, int64_t now_ns) {
  const auto t = mavlink::unpacked<mavlink::Timesync>(f);
  if (t.tc1 == 0) {  // a request: answered in the clock of our time_usec
    mavlink::Timesync answer;
    answer.tc1 = now_ns + sensor_minus_now_ns_;
    answer.ts1 = t.ts1;
    answer.target_system = f.system_id;
    answer.target_component = f.component_id;
    (void)send_now(answer, now_ns);
    ++peer_.timesync_answered;
  } else if (timesync_sent_ns_ >= 0 && t.ts1 == timesync_sent_ts1_) {  // our request's answer
    const int64_t round_trip = now_ns - timesync_sent_ns_;
    timesync_sent_ns_ = -1;
    on_clock_offset(t.tc1 - (t.ts1 + round_trip / 2), round_trip);
  }
}

void PoseLink::on_clock_offset(int64_t offset_ns, int64_t round_trip_ns) {
  // The shortest recent round trip: one lucky answer must not set the bar for the whole run (on
  // a loaded host the path stays slower, and its answers are what there is).
  round_trips_[round_trip_next_] = round_trip_ns;
  round_trip_next_ = (round_trip_next_ + 1) % kRoundTrips;
  round_trip_count_ = std::min(round_trip_count_ + 1, kRoundTrips);
  peer_.best_round_trip_ns = *std::min_element(round_trips_, round_trips_ + round_trip_count_);
  if (round_trip_ns > 2 * peer_.best_round_trip_ns) {  // delayed: its offset is not
    ++peer_.timesync_delayed;
    return;
  }
  // An autopilot that rebooted restarts its clock: smoothing towards it would stamp its
  // attitudes wrongly for tens of seconds, so a jump is taken at once.
  const bool jumped =
      peer_.clock_known && std::llabs(offset_ns - peer_.clock_offset_ns) > kClockJumpNs;
  peer_.clock_jumps += jumped ? 1 : 0;
  peer_.clock_offset_ns = !peer_.clock_known || jumped
                              ? offset_ns
                              : peer_.clock_offset_ns + (offset_ns - peer_.clock_offset_ns) / 5;
  peer_.clock_known = true;
  ++peer_.timesync_replies;
}

void PoseLink::on_attitude(const mavlink::AttitudeQuaternion& a) {
  if (attitudes_ == nullptr) return;
  if (!peer_.clock_known) {
    ++counters_.attitudes_unsynced;
    return;
  }
  AttitudeSample* s = attitudes_->begin_push();
  if (s == nullptr) {
    ++counters_.attitudes_dropped;
    return;
  }
  s->t_ns = static_cast<int64_t>(a.time_boot_ms) * 1'000'000 - peer_.clock_offset_ns;
  s->q_n_b = Eigen::Quaterniond(a.q[0], a.q[1], a.q[2], a.q[3]);
  s->rate_b_rad_s = Vector3d(a.rollspeed, a.pitchspeed, a.yawspeed);
  // The offset is known to half a round trip; time_boot_ms to half a millisecond.
  s->timing_sigma_s = 0.5e-9 * static_cast<double>(peer_.best_round_trip_ns) + 0.5e-3;
  attitudes_->publish();
  ++counters_.attitudes;
}

void PoseLink::listen(int64_t now_ns) {
  // Bounded, so that an endless stream cannot keep the link from sending, but past what an
  // autopilot's flood brings between ticks (10 000 datagrams a second is 333 at 30 Hz): read
  // less than arrives and the backlog grows until its heartbeats arrive seconds late.
  constexpr int kMaxReadsPerTick = 2048;
  uint8_t bytes[512];
  for (int i = 0; i < kMaxReadsPerTick; ++i) {
    const size_t n = link_->receive(bytes, sizeof(bytes));
    if (n == 0) break;
    decoder_.feed_all(bytes, n, [&](const mavlink::Frame& f) { on_frame(f, now_ns); });
  }
  if (peer_.heard && !peer_.silent && now_ns - peer_.last_heartbeat_ns > kPeerSilentNs) {
    peer_.silent = true;
    ++peer_.silences;
    on_status(mavlink::kMavSeverityWarning, "autopilot: silent (no HEARTBEAT for 3 s)", now_ns);
  }
}

void PoseLink::tick(int64_t now_ns, uint8_t system_status) {
  listen(now_ns);
  if (last_heartbeat_ns_ < 0 || now_ns - last_heartbeat_ns_ >= config_.heartbeat_period_ns) {
    last_heartbeat_ns_ = now_ns;
    mavlink::Heartbeat hb;
    hb.system_status = system_status;
    if (send_now(hb, now_ns)) ++counters_.heartbeats_sent;
  }
  // Our own TIMESYNC to a peer that is there measures its clock: once a second, and every
  // 100 ms for its first ten until it answers (its attitudes, and stamps in its clock, wait for
  // that; one that never answers is not flooded).
  constexpr uint32_t kQuickRequests = 10;
  const bool quick = !peer_.clock_known && peer_.timesync_requests < kQuickRequests;
  const int64_t timesync_period_ns = quick ? 100'000'000 : 1'000'000'000;
  if (peer_.heard && !peer_.silent && time_base_set_ &&
      (last_timesync_ns_ < 0 || now_ns - last_timesync_ns_ >= timesync_period_ns)) {
    last_timesync_ns_ = now_ns;
    mavlink::Timesync request;
    request.ts1 = now_ns + sensor_minus_now_ns_;
    request.target_system = peer_.system_id;
    request.target_component = peer_.component_id;
    timesync_sent_ns_ = now_ns;
    timesync_sent_ts1_ = request.ts1;
    (void)send_now(request, now_ns);
    ++peer_.timesync_requests;
  }
  link_->flush();
}

}  // namespace rgbdtam

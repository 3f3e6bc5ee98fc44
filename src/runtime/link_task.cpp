#include "rgbdtam/runtime/link_task.hpp"

#include <chrono>
#include <cstdio>

namespace rgbdtam {

void LinkTask::init(const PoseLinkConfig& config, ByteLink* link, int queue_slots, ClockFn clock) {
  transport_ = link;
  link_.init(config, link);
  queue_.allocate(queue_slots);
  // Half a second of attitudes at 100 Hz: the tracker takes them every frame.
  constexpr int kAttitudeSlots = 64;
  attitudes_.allocate(kAttitudeSlots);
  link_.send_attitudes_to(&attitudes_);
  clock_ = clock;
}

Status LinkTask::start(const ThreadPlacement& placement) {
  // Ticks every 10 ms even without traffic: the heartbeat's 1 Hz, and the autopilot's attitude
  // (50-100 Hz) reaching the tracker before the next frame rather than after it.
  return worker_.start(&queue_, &sender_, placement, "rgbdtam-link", std::chrono::milliseconds(10));
}

bool LinkTask::post(const LinkMessage& m) {
  LinkMessage* slot = queue_.begin_push();
  if (slot == nullptr) {
    queue_drops_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  *slot = m;
  queue_.publish();
  worker_.notify();
  return true;
}

bool LinkTask::post_pose(const PoseEstimate& pose, int64_t arrival_ns,
                         const Eigen::Quaterniond* q_l_w) {
  LinkMessage m;
  m.kind = LinkMessage::Kind::kPose;
  m.pose = pose;
  m.arrival_ns = arrival_ns;
  m.levelled = q_l_w != nullptr;
  if (q_l_w != nullptr) m.q_l_w = *q_l_w;
  return post(m);
}

bool LinkTask::post_status(uint8_t severity, const char* text) {
  LinkMessage m;
  m.kind = LinkMessage::Kind::kStatus;
  m.severity = severity;
  std::snprintf(m.text, sizeof(m.text), "%s", text);
  return post(m);
}

bool LinkTask::post_obstacles(const ObstacleSectors& sectors, int64_t timestamp_ns) {
  LinkMessage m;
  m.kind = LinkMessage::Kind::kObstacles;
  m.obstacles = sectors;
  m.obstacles_timestamp_ns = timestamp_ns;
  return post(m);
}

void LinkTask::stop() {
  if (worker_.running()) worker_.stop();
}

void LinkTask::Sender::step(const LinkMessage& m) {
  const int64_t t0 = task->clock_();
  switch (m.kind) {
    case LinkMessage::Kind::kPose: {
      const uint64_t sent = task->link_.counters().odometry_sent;
      task->link_.set_time_base(m.pose.timestamp_ns, m.arrival_ns);
      if (m.levelled) task->link_.set_level(m.q_l_w);
      task->link_.on_pose(m.pose, t0);
      if (task->link_.counters().odometry_sent != sent) {
        task->arrival_to_odometry_.add(task->clock_() - m.arrival_ns);
      }
      break;
    }
    case LinkMessage::Kind::kStatus:
      task->link_.on_status(m.severity, m.text, t0);
      break;
    case LinkMessage::Kind::kObstacles:
      task->link_.on_obstacles(m.obstacles, m.obstacles_timestamp_ns, t0);
      break;
  }
  task->per_message_.add(task->clock_() - t0);
}

void LinkTask::Sender::tick() {
  const int64_t now = task->clock_();
  task->link_.tick(now, task->system_status_.load(std::memory_order_relaxed));
  task->clock_known_.store(task->link_.peer().clock_known, std::memory_order_release);
  // Once a second, the latency so far, for a ground station or the monitor to show.
  const LatencyStats& latency = task->arrival_to_odometry_;
  if (latency.count() > 0 && now - task->latency_reported_ns_ >= 1'000'000'000) {
    task->latency_reported_ns_ = now;
    task->link_.on_latency(static_cast<float>(latency.percentile_ms(0.5)),
                           static_cast<float>(latency.percentile_ms(0.95)),
                           static_cast<float>(latency.max_ms()), now);
  }
}

void LinkTask::Sender::finish() {
  // Give a serial port the time its queued bytes need (at most a second).
  for (int i = 0; i < 100 && task->transport_->flush() > 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace rgbdtam

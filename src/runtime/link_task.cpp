#include "rgbdtam/runtime/link_task.hpp"

#include <chrono>
#include <cstring>

namespace rgbdtam {

LinkTask::~LinkTask() {
  if (thread_.joinable()) stop();
}

void LinkTask::init(const PoseLinkConfig& config, ByteLink* link, int queue_slots, ClockFn clock) {
  transport_ = link;
  link_.init(config, link);
  queue_.allocate(queue_slots);
  clock_ = clock;
}

Status LinkTask::start(const ThreadPlacement& placement) {
  stopping_ = false;
  thread_ = std::thread([this] { run(); });
  return place_thread(thread_, placement, "rgbdtam-link");
}

bool LinkTask::post(const LinkMessage& m) {
  LinkMessage* slot = queue_.begin_push();
  if (slot == nullptr) {
    queue_drops_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  *slot = m;
  queue_.publish();
  wake_.notify_one();
  return true;
}

bool LinkTask::post_pose(const PoseEstimate& pose, int64_t arrival_ns) {
  LinkMessage m;
  m.kind = LinkMessage::Kind::kPose;
  m.pose = pose;
  m.arrival_ns = arrival_ns;
  return post(m);
}

bool LinkTask::post_status(uint8_t severity, const char* text) {
  LinkMessage m;
  m.kind = LinkMessage::Kind::kStatus;
  m.severity = severity;
  std::strncpy(m.text, text, sizeof(m.text) - 1);
  return post(m);
}

void LinkTask::stop() {
  stopping_.store(true, std::memory_order_release);
  wake_.notify_one();
  thread_.join();
}

void LinkTask::run() {
  // The heartbeat's 1 Hz needs a turn at least every 100 ms even without traffic.
  constexpr auto kIdle = std::chrono::milliseconds(100);
  for (;;) {
    while (LinkMessage* m = queue_.front()) {
      const int64_t t0 = clock_();
      if (m->kind == LinkMessage::Kind::kPose) {
        link_.set_time_base(m->pose.timestamp_ns, m->arrival_ns);
        link_.on_pose(m->pose, t0);
      } else {
        link_.on_status(m->severity, m->text, t0);
      }
      queue_.pop();
      per_message_.add(clock_() - t0);
    }
    link_.tick(clock_(), system_status_.load(std::memory_order_relaxed));
    if (stopping_.load(std::memory_order_acquire) && queue_.front() == nullptr) break;
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait_for(lock, kIdle, [this] {
      return stopping_.load(std::memory_order_acquire) || queue_.front() != nullptr;
    });
  }
  // Give a serial port the time its queued bytes need (at most a second).
  for (int i = 0; i < 100 && transport_->flush() > 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace rgbdtam

#pragma once
// The link task: its own thread takes poses and events from the tracker through a bounded
// SPSC queue and hands them to the PoseLink (MAVLink over a ByteLink). The tracker never
// waits: a full queue drops the message and counts it.

#include <atomic>

#include "rgbdtam/port/latency_stats.hpp"
#include "rgbdtam/port/spsc_ring.hpp"
#include "rgbdtam/port/thread_placement.hpp"
#include "rgbdtam/port/worker.hpp"
#include "rgbdtam/runtime/pose_link.hpp"

namespace rgbdtam {

class LinkTask {
 public:
  void init(const PoseLinkConfig& config, ByteLink* link, int queue_slots, ClockFn clock);
  Status start(const ThreadPlacement& placement);
  // Tracker thread. False when the queue was full (the message is dropped and counted).
  // q_l_w: the level frame ODOMETRY is sent in, once known (null: not yet).
  bool post_pose(const PoseEstimate& pose, int64_t arrival_ns,
                 const Eigen::Quaterniond* q_l_w = nullptr);
  // Tracker thread: the autopilot's attitudes received since the last call, oldest first.
  template <typename OnSample>
  void take_attitudes(OnSample&& on_sample) {
    while (const AttitudeSample* s = attitudes_.front()) {
      on_sample(*s);
      attitudes_.pop();
    }
  }
  // Tracker thread: attitudes received and not yet taken.
  int attitudes_waiting() const { return attitudes_.size(); }
  // Any thread: the autopilot's clock is known (its TIMESYNC answered), so its attitudes are
  // taken; before that they are counted as unsynced and dropped.
  bool autopilot_clock_known() const { return clock_known_.load(std::memory_order_acquire); }
  bool post_status(uint8_t severity, const char* text);
  // timestamp_ns: the depth frame's, in the sensor's clock (as the poses' stamps).
  bool post_obstacles(const ObstacleSectors& sectors, int64_t timestamp_ns);
  // MAV_STATE for the heartbeat.
  void set_system_status(uint8_t state) { system_status_.store(state, std::memory_order_relaxed); }
  // Sends what is queued, then joins.
  void stop();

  uint64_t queue_drops() const { return queue_drops_.load(std::memory_order_relaxed); }
  // Read after stop().
  const PoseLinkCounters& counters() const { return link_.counters(); }
  const PeerState& peer() const { return link_.peer(); }
  const LatencyStats& time_per_message() const { return per_message_; }
  // From a frame's arrival (the sensor handing it over) to its ODOMETRY written to the
  // transport, for each ODOMETRY sent: what an autopilot's vision delay parameter must cover on
  // top of the sensor's own capture-to-arrival time.
  const LatencyStats& arrival_to_odometry() const { return arrival_to_odometry_; }

 private:
  // The module on the link's thread.
  struct Sender {
    LinkTask* task;
    void step(const LinkMessage& m);
    void tick();
    void finish();
  };
  bool post(const LinkMessage& m);

  PoseLink link_;
  ByteLink* transport_ = nullptr;
  SpscRing<LinkMessage> queue_;
  SpscRing<AttitudeSample> attitudes_;  // link thread -> tracker thread
  ClockFn clock_ = nullptr;
  LatencyStats per_message_;
  LatencyStats arrival_to_odometry_;
  int64_t latency_reported_ns_ = 0;
  std::atomic<uint8_t> system_status_{3};  // MAV_STATE_STANDBY
  std::atomic<uint64_t> queue_drops_{0};
  std::atomic<bool> clock_known_{false};
  Sender sender_{this};
  WorkerThread<LinkMessage, Sender> worker_;
};

}  // namespace rgbdtam

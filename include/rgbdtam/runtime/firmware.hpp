#pragma once
// The firmware runtime on a board: the tracker task at the sensor's cadence on the caller's
// thread, the mapper and the link on their own threads (placed as the board says), the status
// LED and frame trigger on GPIO. Modules talk only through bounded SPSC queues of fixed-size
// messages (tracker -> mapper frames, tracker -> link poses and events).
//
// Cadence: each frame's deadline is one sensor period after the sensor delivered it. The
// tracker never blocks; when it falls behind, the sensor side keeps the newest frame and
// drops the older ones (counted there), and every frame finishing after its deadline is
// counted here as a miss.

#include <cstdint>

#include "rgbdtam/core/obstacle_sectors.hpp"
#include "rgbdtam/port/latency_stats.hpp"
#include "rgbdtam/runtime/attitude_aid.hpp"
#include "rgbdtam/runtime/board.hpp"
#include "rgbdtam/runtime/link_task.hpp"
#include "rgbdtam/runtime/slam_system.hpp"
#include "rgbdtam/runtime/status_led.hpp"

namespace rgbdtam {

struct FirmwareCounters {
  uint32_t frames = 0;
  uint32_t tracked = 0;
  uint32_t lost = 0;
  uint32_t deadline_misses = 0;
  uint32_t sensor_errors = 0;
  uint32_t sensor_recoveries = 0;      // frames flowing again after a stall
  uint32_t status_texts = 0;           // events posted to the link
  uint32_t sensor_texts_withheld = 0;  // sensor errors not posted: one already was, lately
  uint32_t obstacle_reports = 0;       // OBSTACLE_DISTANCE handed to the link
};

class FirmwareRuntime {
 public:
  static constexpr int kLinkQueueSlots = 16;
  // Allocates everything. The mapper always runs on its own thread here.
  // vocabulary: for loop closure and relocalisation (null: off).
  Status init(const Params& params, const Board& board, ByteLink* link, GpioOutputs* gpio,
              ClockFn clock, const Vocabulary* vocabulary = nullptr);
  // The params init gives the SLAM system on this board (its memory_need is the system's).
  static Params system_params(const Params& params, const Board& board);
  // After init, before start: a saved map to start in (SlamSystem::load_map); the first pose
  // found in it is announced on the link.
  Status load_map(const uint8_t* data, size_t size, MapFileInfo* info);
  // After init, before start: saves while running (SlamSystem::set_checkpoint).
  Status set_map_checkpoint(MapCheckpoint* checkpoint) { return slam_.set_checkpoint(checkpoint); }
  // Places the calling thread as the tracker and starts the mapper and link threads, as the
  // board says. on_frame() must then be called from this same thread.
  Status start();
  // The tracker task for one frame the sensor delivered at arrival_ns.
  PoseEstimate on_frame(const SensorFrame& frame, int64_t arrival_ns);
  // A frame the sensor could not deliver (its message goes to the link).
  void on_sensor_error(const Status& error, int64_t now_ns);
  // Frames flow again after a stall of outage_ns (last frame to this one).
  void on_sensor_recovered(int64_t outage_ns);
  // Lets the mapper and the link finish, and joins them.
  void stop();

  const FirmwareCounters& counters() const { return counters_; }
  const LatencyStats& tracker_time() const { return tracker_time_; }
  const SlamSystem& slam() const { return slam_; }
  const LinkTask& link() const { return link_; }
  const AttitudeAid& attitude() const { return attitude_; }
  const StatusLed& led() const { return led_; }

 private:
  void post_event(uint8_t severity, const char* text);
  // OBSTACLE_DISTANCE at obstacle.rate_hz, from the frame's depth (tracker thread: a 4x4
  // subsample of the image, a few tenths of a millisecond).
  void report_obstacles(const SensorFrame& frame);
  void report_stores_full();  // once each, when the keyframe pool or the place store first fills

  Params params_;
  Board board_;
  ClockFn clock_ = nullptr;
  GpioOutputs* gpio_ = nullptr;
  int64_t period_ns_ = 0;
  SlamSystem slam_;
  LinkTask link_;
  AttitudeAid attitude_;  // the autopilot's attitude, on the tracker's thread
  StatusLed led_;
  LatencyStats tracker_time_;
  bool sensor_text_posted_ = false;  // this outage has been reported, at sensor_text_ns_
  int64_t sensor_text_ns_ = 0;
  FirmwareCounters counters_;
  bool lost_ = false;
  bool pool_full_reported_ = false;
  bool place_store_full_reported_ = false;
  bool localising_ = false;     // a map was loaded and no pose has been found in it yet
  int64_t fault_until_ns_ = 0;  // the LED shows a fault for a while after a sensor error
  ObstacleSectorizer obstacles_;
  BlindedSectors blinded_;
  int64_t obstacle_period_ns_ = 0;  // 0: not sent
  int64_t last_obstacles_ns_ = INT64_MIN / 2;
  bool started_ = false;
};

}  // namespace rgbdtam

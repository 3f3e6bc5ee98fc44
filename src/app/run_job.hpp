#pragma once
// `rgbdtam run --board board/<name>`: the firmware runtime on a board definition. The sensor,
// link and GPIO backends are chosen from the board's data; host emulation is the replay sensor
// paced at its recorded rate, UDP on loopback and the fake GPIO chip.

#include <atomic>
#include <memory>

#include "rgbdtam/hal/atomic_file.hpp"
#include "rgbdtam/hal/gpio.hpp"
#include "rgbdtam/hal/replay_sensor.hpp"
#include "rgbdtam/hal/sensor_recovery.hpp"
#include "rgbdtam/hal/v4l2_source.hpp"
#if RGBDTAM_WITH_FREENECT
#include "rgbdtam/hal/freenect_source.hpp"
#endif
#if RGBDTAM_WITH_OPENNI2
#include "rgbdtam/hal/openni2_source.hpp"
#endif
#include "rgbdtam/runtime/firmware.hpp"
#include "rgbdtam/runtime/registering_sensor.hpp"

namespace rgbdtam {

struct RunOptions {
  const char* board_dir = nullptr;
  static constexpr int kMaxOverrides = 32;
  const char* board_overrides[kMaxOverrides] = {};  // key=value on the board
  int board_override_count = 0;
  const char* param_overrides[kMaxOverrides] = {};  // key=value on its params file
  int param_override_count = 0;
  int max_frames = 0;  // 0: the whole stream
  bool progress = true;
  V4l2Io* v4l2_io =
      nullptr;  // a v4l2 board's system calls; null: the real ones (a soak fakes them)
  const char* written_by = "rgbdtam";  // the build, recorded in a saved map
  // A replay board's frames are never dropped: each waits until the tracker took the one before
  // (a test's run is then the same on a busy machine, only slower). Other sensors ignore it.
  bool replay_every_frame = false;
};

// The board with its overrides, validated, and its params file with theirs.
Status load_board_and_params(const RunOptions& options, Board* board, Params* params);
// Whether this build has the backend a sensor.kind names (RGBDTAM_HAL_BACKENDS lists them).
bool sensor_backend_in_build(const char* kind);
// "this build has no '<kind>' sensor backend (it has: ...)", naming the board.
Status missing_backend_error(const Board& board);
// The board's sensor, whichever backend its sensor.kind names (those this build has).
struct BoardSensor {
  TumReplaySource replay;
  ReplaySensor replay_sensor;
  SystemV4l2Io v4l2_io;
  V4l2Source v4l2;
#if RGBDTAM_WITH_FREENECT
  FreenectSource freenect;
#endif
#if RGBDTAM_WITH_OPENNI2
  OpenNi2Source openni2;
#endif
  RegisteringSensor registering;  // the backend on a thread of its own (registration_thread)
  SensorRecovery recovery;        // wraps whichever backend is open
  LiveSensor* live = nullptr;
};
Status open_board_sensor(const Board& board, const Params& params, BoardSensor* sensor,
                         V4l2Io* v4l2_io = nullptr);

class RunJob {
 public:
  ~RunJob();
  // Allocates everything; starts no thread.
  Status init(const RunOptions& options);
  // Starts the sensor, mapper and link threads.
  Status start();
  // One frame at the sensor's cadence; false at the end of the stream or after request_stop().
  bool step();
  void request_stop() { stop_requested_.store(true); }
  // Lets the mapper and the link finish, and joins them; then saves the board's map.file.
  void finish();
  // After finish(): an error when map.file was to be saved and was not, saying what the file
  // holds instead; ok otherwise.
  Status final_map_save() const;
  void print_summary() const;
  // The board's map.file: what was loaded (places = 0: none), and how saving it went.
  const MapFileInfo& loaded_map() const { return loaded_map_; }
  const Status& map_saved() const { return map_saved_; }
  // Saves while running (map.save_period_s): how many, and how many failed.
  const MapCheckpoint& map_checkpoint() const { return checkpoint_; }

  const FirmwareRuntime& runtime() const { return *runtime_; }
  const Board& board() const { return board_; }
  uint32_t sensor_dropped() const { return sensor_.live->dropped(); }
  const ByteLink& link() const { return *link_; }
  const GpioOutputs* gpio() const { return gpio_.get(); }

 private:
  RunOptions options_;
  Board board_;
  Params params_;
  Vocabulary vocabulary_;
  BoardSensor sensor_;
  std::unique_ptr<ByteLink> link_;
  std::unique_ptr<GpioOutputs> gpio_;
  Status open_map_file(bool loop);
  void print_task_times() const;
  void print_map_file_summary() const;
  void print_link_summary() const;

  std::unique_ptr<FirmwareRuntime> runtime_;
  MapFileInfo loaded_map_;
  Status map_saved_;
  AtomicFileWriter checkpoint_file_;
  MapCheckpoint checkpoint_;
  std::atomic<bool> stop_requested_{false};
  int64_t started_ns_ = 0;
  int64_t last_progress_ns_ = 0;
  uint64_t memory_needed_bytes_ = 0;
  int64_t wall_ns_ = 0;
  uint32_t recoveries_reported_ = 0;
  bool started_ = false;  // the runtime's threads run: finish() stops them and saves the map
  bool finished_ = false;
};

}  // namespace rgbdtam

#pragma once
// Replays a recorded sequence through the tracking pipeline: source -> pipeline -> writer.
// init() allocates everything; step() processes one frame without allocating.

#include <atomic>
#include <vector>

#include "evaluate_command.hpp"
#include "map_files.hpp"
#include "rgbdtam/core/evaluation.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/port/latency_stats.hpp"
#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {

struct ReplayOptions {
  const char* sequence = nullptr;
  const char* trajectory_path = nullptr;  // optional
  // Optional: the covariance sent with each pose of the trajectory (rgbdtam eval --covariance).
  const char* covariance_path = nullptr;
  // Optional: every tracked frame again at the end, placed on its keyframe as the final map
  // has it (after loop closures), as offline SLAM evaluations report.
  const char* final_trajectory_path = nullptr;
  MapSink* map_sink = nullptr;  // optional: receives each keyframe's map
  // Optional: a map file to start in (its places and graph), and one to save the final map to.
  const char* map_in_path = nullptr;
  const char* map_out_path = nullptr;
  const char* written_by = "rgbdtam";     // the build, recorded in a saved map
  LoopObserver* loop_observer = nullptr;  // optional: every verified place match
  Params params;
  bool progress = true;
  int max_frames = 0;  // 0 = all
  // Each frame at its recorded time, as the sensor delivered it (else as fast as it goes), so
  // that modules on threads of their own (map.threaded) keep the pace they would keep live.
  bool paced = false;
  // Optional, synchronous mode only: a CSV line per frame of each module's time in it, for
  // tools/task_sim.py, which replays it through a board's task table.
  const char* trace_path = nullptr;
};

class ReplayJob {
 public:
  Status init(const ReplayOptions& options);
  // Processes the next frame; false when the sequence has ended, after request_stop(), or
  // when the trajectory cannot be written (finish() says why).
  bool step();
  void request_stop() { stop_requested_.store(true); }  // async-signal-safe
  bool stopped_early() const { return stop_requested_.load(); }
  Status finish();  // the trajectory complete and in place, or the first failure
  Status write_trace() const;
  void print_summary() const;
  // What the user must hear about the sensor's data (stderr), in either output mode.
  void print_warnings() const;
  // The summary and the evaluation as one JSON object, for tools/bench.sh.
  void print_json(const EvaluationReport& report) const;

  const PoseEstimate& last_pose() const { return last_pose_; }
  const std::vector<StampedPose>& estimates() const { return estimates_; }
  // After finish(): every tracked frame (withheld ones too) on its keyframe's final pose.
  const std::vector<StampedPose>& final_estimates() const { return final_estimates_; }
  // Of each estimate: the reported pose covariance, (translation, rotation) in the camera.
  const std::vector<Eigen::Matrix<double, 6, 6>>& covariances() const { return covariances_; }
  TrackingCounters counters() const { return system_.tracking().counters(); }
  const LatencyStats& tracking_time() const { return tracking_ms_; }
  const LatencyStats& frame_time() const { return frame_ms_; }
  const TumReplaySource& source() const { return source_; }
  const MappingModule& mapper() const { return system_.mapper(); }
  bool loop_enabled() const { return system_.loop_enabled(); }
  const LoopModule& loop() const { return system_.loop(); }
  const SlamSystem& system() const { return system_; }
  // What the loaded map held (places = 0 when none was).
  const MapFileInfo& loaded_map() const { return loaded_map_; }
  int found_in_map_at_frame() const { return found_in_map_at_frame_; }

 private:
  ReplayOptions options_;
  TumReplaySource source_;
  Vocabulary vocabulary_;  // before system_, which refers to it
  SlamSystem system_;
  TrajectoryWriter writer_;
  TrajectoryWriter covariance_writer_;
  std::vector<StampedPose> estimates_;                    // reserved for every frame at init
  std::vector<Eigen::Matrix<double, 6, 6>> covariances_;  // the same
  struct OnKeyframe {
    double t_s;
    uint32_t keyframe_id;
    SE3 T_w_c;  // as reported
    SE3 T_k_c;  // on its keyframe, when the keyframe was found
    bool on_keyframe;
  };
  std::vector<OnKeyframe> on_keyframes_;  // the same
  std::vector<StampedPose> final_estimates_;
  LatencyStats tracking_ms_, frame_ms_;
  int64_t first_frame_ns_ = -1, first_stamp_ns_ = 0;  // paced: the sequence's start
  LatencyStats tracker_thread_ms_;  // tracking and keyframe orders, without the build
  struct TraceRow {
    int64_t stamp_ns, sensor_ns, tracker_ns, build_ns;
    bool keyframe;
    SlamSystem::Steps mapper, loop;
  };
  std::vector<TraceRow> trace_;
  PoseEstimate last_pose_;
  int processed_ = 0;
  int reported_problems_ = 0;
  std::atomic<bool> stop_requested_{false};
  Status write_failure_;
  uint64_t memory_needed_bytes_ = 0;
  MapFileInfo loaded_map_;
  int found_in_map_at_frame_ = -1;  // the first valid pose's frame (from 0) after loading
  int64_t map_load_ns_ = 0, map_save_ns_ = 0;
  int64_t started_ns_ = 0, finished_ns_ = 0;
};

}  // namespace rgbdtam

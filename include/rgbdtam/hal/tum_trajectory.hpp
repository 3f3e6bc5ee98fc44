#pragma once
// TUM trajectory files: `timestamp tx ty tz qx qy qz qw`, camera-to-world, metres.

#include <cstdio>
#include <vector>

#include "rgbdtam/core/evaluation.hpp"
#include "rgbdtam/core/status.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/port/messages.hpp"

namespace rgbdtam {

// Host-side reader for evaluation (allocates). Lines that do not parse are counted, not fatal.
Status read_tum_trajectory(const char* path, std::vector<StampedPose>* out, int* bad_lines);
// The same from text (written to while parsing), sorted by time.
void parse_tum_trajectory(char* text, std::vector<StampedPose>* out, int* bad_lines);
// Timestamps of an rgb.txt-style list, in seconds.
Status read_tum_stamps(const char* path, std::vector<double>* out);

// A pose's covariance as sent with it (TrajectoryContent::kCovariance files).
struct StampedCovariance {
  double stamp_s;
  Matrix6d covariance;
};
Status read_tum_covariances(const char* path, std::vector<StampedCovariance>* out, int* bad_lines);

// What a trajectory file holds per tracked frame: its pose, or the covariance sent with it
// (the link's numbers in the camera frame: the upper triangle row by row over x, y, z and the
// rotation about them, as MAVLink's ODOMETRY.pose_covariance orders it).
enum class TrajectoryContent { kPoses, kCovariance };

// Streams one line per valid pose through a buffer owned by the writer; no allocation. The
// lines reach the disk at least once a second (an interrupted run keeps them, as
// `<path>.partial`); close() renames the file into place.
class TrajectoryWriter {
 public:
  Status open(const char* path, TrajectoryContent content = TrajectoryContent::kPoses);
  // The first write failure, naming the file and the reason; every later write returns it too.
  Status write(const PoseEstimate& pose);
  Status close();

 private:
  OutputFile file_;
  TrajectoryContent content_ = TrajectoryContent::kPoses;
  int64_t flushed_ns_ = 0;
  char buffer_[1 << 16];
};

}  // namespace rgbdtam

#include "rgbdtam/hal/tum_trajectory.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "rgbdtam/core/text_lines.hpp"
#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"
#include "rgbdtam/hal/tum_timestamp.hpp"

namespace rgbdtam {
namespace {
constexpr size_t kMaxTrajectoryBytes = 256u << 20;
}

namespace {
constexpr int kCovarianceValues = 21;  // the upper triangle, row by row

// Each data line's first `count` finite numbers (commas and tabs as spaces, '#' comments),
// given to take(), which says whether they are a valid record; the others are counted bad.
template <typename Take>
void parse_lines(char* text, int count, int* bad_lines, Take take) {
  *bad_lines = 0;
  for (char* line = text; line != nullptr && *line != '\0';) {
    size_t length = 0;
    char* next = const_cast<char*>(split_line(line, &length));
    line[length] = '\0';
    for (char* c = line; *c != '\0'; ++c)
      if (*c == ',' || *c == '\t') *c = ' ';
    const char* s = line;
    while (*s == ' ') ++s;
    if (*s != '\0' && *s != '#') {
      double v[1 + kCovarianceValues];
      int n = 0;
      char* cur = const_cast<char*>(s);
      for (; n < count; ++n) {
        char* end = nullptr;
        v[n] = std::strtod(cur, &end);
        if (end == cur || !std::isfinite(v[n])) break;
        cur = end;
      }
      if (n < count || !take(v)) ++*bad_lines;
    }
    line = next;
  }
}
}  // namespace

void parse_tum_trajectory(char* text, std::vector<StampedPose>* out, int* bad_lines) {
  out->clear();
  parse_lines(text, 8, bad_lines, [&](const double* v) {
    // evaluate_rpe.py skips zero quaternions as well. A quaternion far from unit length or a
    // position beyond any map is a broken line, not a pose to normalise or average in.
    constexpr double kMostQuaternionNormError = 0.01, kMostMetres = 1e6;
    const double q_norm = Eigen::Quaterniond(v[7], v[4], v[5], v[6]).norm();
    if (!(std::fabs(q_norm - 1.0) <= kMostQuaternionNormError)) return false;
    for (int k = 1; k <= 3; ++k) {
      if (!(std::fabs(v[k]) <= kMostMetres)) return false;
    }
    out->push_back(
        {v[0], SE3(Eigen::Quaterniond(v[7], v[4], v[5], v[6]), Vector3d(v[1], v[2], v[3]))});
    return true;
  });
  std::stable_sort(out->begin(), out->end(), [](const StampedPose& a, const StampedPose& b) {
    return a.stamp_s < b.stamp_s;
  });
}

Status read_tum_covariances(const char* path, std::vector<StampedCovariance>* out, int* bad_lines) {
  char* text = nullptr;
  RGBDTAM_RETURN_IF_ERROR(read_text_file(path, kMaxTrajectoryBytes, &text));
  out->clear();
  parse_lines(text, 1 + kCovarianceValues, bad_lines, [&](const double* v) {
    StampedCovariance c{v[0], Matrix6d::Zero()};
    for (int r = 0, k = 1; r < 6; ++r) {
      for (int col = r; col < 6; ++col, ++k) c.covariance(r, col) = c.covariance(col, r) = v[k];
    }
    // A covariance has non-negative variances.
    if (!(c.covariance.diagonal().minCoeff() >= 0.0)) return false;
    out->push_back(c);
    return true;
  });
  delete[] text;
  std::stable_sort(
      out->begin(), out->end(),
      [](const StampedCovariance& a, const StampedCovariance& b) { return a.stamp_s < b.stamp_s; });
  if (out->empty()) return Status::error(StatusCode::kCorrupt, "%s: no covariances", path);
  return Status::ok();
}

Status read_tum_trajectory(const char* path, std::vector<StampedPose>* out, int* bad_lines) {
  char* text = nullptr;
  RGBDTAM_RETURN_IF_ERROR(read_text_file(path, kMaxTrajectoryBytes, &text));
  parse_tum_trajectory(text, out, bad_lines);
  delete[] text;
  if (out->empty()) return Status::error(StatusCode::kCorrupt, "%s: no poses", path);
  // One instant, two poses: which one the association takes would decide the error.
  for (size_t i = 1; i < out->size(); ++i) {
    const StampedPose& a = (*out)[i - 1];
    const StampedPose& b = (*out)[i];
    if (a.stamp_s == b.stamp_s &&
        (a.T_w_c.translation() != b.T_w_c.translation() ||
         a.T_w_c.quaternion().coeffs() != b.T_w_c.quaternion().coeffs())) {
      return Status::error(StatusCode::kCorrupt,
                           "%s: stamp %.6f is listed twice with different poses", path, a.stamp_s);
    }
  }
  return Status::ok();
}

Status read_tum_stamps(const char* path, std::vector<double>* out) {
  char* text = nullptr;
  RGBDTAM_RETURN_IF_ERROR(read_text_file(path, kMaxTrajectoryBytes, &text));
  TumList list;
  const Status s = parse_tum_list(text, path, &list);
  delete[] text;
  RGBDTAM_RETURN_IF_ERROR(s);
  out->clear();
  for (int i = 0; i < list.size; ++i) out->push_back(list.entries[i].timestamp_ns * 1e-9);
  return Status::ok();
}

Status TrajectoryWriter::open(const char* path, TrajectoryContent content) {
  content_ = content;
  RGBDTAM_RETURN_IF_ERROR(file_.open(path, buffer_, sizeof(buffer_)));
  flushed_ns_ = monotonic_ns();
  const char* header =
      content == TrajectoryContent::kPoses
          ? "# timestamp tx ty tz qx qy qz qw (camera to world, every tracked frame)\n"
          : "# timestamp and the covariance of each tracked frame's pose sent with it: 21 values, "
            "the upper triangle row by row over (x, y, z, rotation about x, y, z) in the camera "
            "frame, m^2 and rad^2\n";
  return file_.check(std::fputs(header, file_.stream()) >= 0);
}

Status TrajectoryWriter::write(const PoseEstimate& pose) {
  if (!file_.is_open() || (pose.flags & kPoseValid) == 0) return file_.status();
  RGBDTAM_RETURN_IF_ERROR(file_.status());
  char stamp[32];
  format_seconds(pose.timestamp_ns, stamp, sizeof(stamp));
  if (content_ == TrajectoryContent::kPoses) {
    const Vector3d& t = pose.T_w_c.translation();
    const Eigen::Quaterniond& q = pose.T_w_c.quaternion();
    RGBDTAM_RETURN_IF_ERROR(
        file_.check(std::fprintf(file_.stream(), "%s %.7f %.7f %.7f %.7f %.7f %.7f %.7f\n", stamp,
                                 t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()) >= 0));
  } else {
    // A pose sent without a covariance (the first, the world's origin) has no line.
    const Matrix6d c = pose_covariance(pose);
    if (!c.allFinite()) return Status::ok();
    RGBDTAM_RETURN_IF_ERROR(file_.check(std::fputs(stamp, file_.stream()) >= 0));
    for (int r = 0; r < 6; ++r) {
      for (int col = r; col < 6; ++col) {
        RGBDTAM_RETURN_IF_ERROR(file_.check(std::fprintf(file_.stream(), " %.9g", c(r, col)) >= 0));
      }
    }
    RGBDTAM_RETURN_IF_ERROR(file_.check(std::fputc('\n', file_.stream()) != EOF));
  }
  constexpr int64_t kFlushEveryNs = 1'000'000'000;
  const int64_t now = monotonic_ns();
  if (now - flushed_ns_ < kFlushEveryNs) return Status::ok();
  flushed_ns_ = now;
  return file_.flush();
}

Status TrajectoryWriter::close() { return file_.commit(); }

}  // namespace rgbdtam

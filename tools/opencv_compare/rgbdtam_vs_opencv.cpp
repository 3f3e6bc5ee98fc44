// The same frames through rgbdtam's tracker and OpenCV's RgbdOdometry, one after the other in
// one process, one thread each (our mapper on its own thread, as on a board):
//   rgbdtam-vs-opencv <sequence> --config <file> [--max-frames N] [--set key=value]...
// Prints each one's per-frame median and p95, their ratio, and each one's all-frames ATE.
// OpenCV's time is its odometry call alone, each frame's pyramid built once (its frame cache);
// it gets the images undecoded already and does not undistort, so the comparison favours it.
// A host tool: OpenCV (Debian's contrib packages) is linked dynamically, never into rgbdtam.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/rgbd.hpp>

#include "config_files.hpp"
#include "evaluate_command.hpp"
#include "replay_job.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"

namespace rgbdtam {
namespace {

int fail(const char* what) {
  std::fprintf(stderr, "rgbdtam-vs-opencv: %s\n", what);
  return 1;
}

std::vector<double> frame_stamps(const TumReplaySource& source) {
  std::vector<double> stamps;
  for (int i = 0; i < source.rgb_list().size; ++i) {
    stamps.push_back(static_cast<double>(source.rgb_list().entries[i].timestamp_ns) * 1e-9);
  }
  return stamps;
}

// Ours: the replay path of `rgbdtam replay`, its tracking time (decoded frame to pose).
bool run_ours(const std::string& sequence, const Params& params, int max_frames,
              std::vector<StampedPose>* estimates, std::vector<double>* stamps, LatencyStats* t) {
  ReplayOptions opt;
  opt.sequence = sequence.c_str();
  opt.params = params;
  opt.progress = false;
  opt.max_frames = max_frames;
  ReplayJob job;
  if (!job.init(opt).is_ok()) return false;
  while (job.step()) {
  }
  if (!job.finish().is_ok()) return false;
  *t = job.tracking_time();
  *estimates = job.estimates();
  *stamps = frame_stamps(job.source());
  return true;
}

bool run_opencv(const std::string& sequence, const Params& params, int max_frames,
                std::vector<StampedPose>* estimates, LatencyStats* t) {
  if (params.depth_camera.register_to_colour) {
    return fail("OpenCV's RgbdOdometry takes depth registered to colour (depth_camera.register)") ==
           0;
  }
  TumReplaySource source;
  const Status s =
      source.open(sequence.c_str(), sensor_image_size(params), params.sensor.max_rgb_depth_dt_ns,
                  params.sensor.depth_time_offset_ns);
  if (!s.is_ok()) return fail(s.message()) == 0;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << params.camera.fx_px, 0, params.camera.cx_px, 0,
                     params.camera.fy_px, params.camera.cy_px, 0, 0, 1);
  cv::Ptr<cv::rgbd::RgbdOdometry> odometry =
      cv::rgbd::RgbdOdometry::create(K, static_cast<float>(params.sensor.depth_range.min_m),
                                     static_cast<float>(params.sensor.depth_range.max_m));
  cv::Ptr<cv::rgbd::OdometryFrame> previous;
  cv::Mat T_w_c = cv::Mat::eye(4, 4, CV_64FC1);
  for (int i = 0; max_frames == 0 || i < max_frames; ++i) {
    SensorFrame f;
    Status warning;
    const Status r = source.next(&f, &warning);
    if (r.code() == StatusCode::kEndOfStream) break;
    if (!r.is_ok() || f.depth == nullptr) continue;
    const cv::Mat gray(f.height_px, f.width_px, CV_8UC1, const_cast<uint8_t*>(f.gray));
    const cv::Mat raw(f.height_px, f.width_px, CV_16UC1, const_cast<uint16_t*>(f.depth));
    cv::Mat depth;
    raw.convertTo(depth, CV_32FC1, 1.0 / params.sensor.depth_factor);
    cv::Ptr<cv::rgbd::OdometryFrame> current = cv::rgbd::OdometryFrame::create(gray.clone(), depth);
    const double stamp_s = static_cast<double>(f.timestamp_ns) * 1e-9;
    if (previous.empty()) {
      odometry->prepareFrameCache(current, cv::rgbd::OdometryFrame::CACHE_ALL);
      estimates->push_back({stamp_s, SE3()});
    } else {
      cv::Mat Rt;
      const auto t0 = std::chrono::steady_clock::now();
      const bool ok = odometry->compute(previous, current, Rt);
      const auto t1 = std::chrono::steady_clock::now();
      t->add(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count());
      if (ok) {
        T_w_c = T_w_c * Rt.inv();  // Rt maps the previous camera's points into the current's
        Eigen::Matrix4d T;
        for (int r0 = 0; r0 < 4; ++r0)
          for (int c = 0; c < 4; ++c) T(r0, c) = T_w_c.at<double>(r0, c);
        estimates->push_back(
            {stamp_s, SE3(Eigen::Quaterniond(Eigen::Matrix3d(T.topLeftCorner<3, 3>())),
                          Eigen::Vector3d(T.topRightCorner<3, 1>()))});
      }
    }
    previous = current;
  }
  return true;
}

int run(int argc, char** argv) {
  if (argc < 4 || std::strcmp(argv[2], "--config") != 0) {
    return fail(
        "usage: rgbdtam-vs-opencv <sequence> --config <file> [--max-frames N] "
        "[--set key=value]...");
  }
  const std::string sequence = argv[1];
  Params params;
  Status s = read_params_file(argv[3], &params);
  if (!s.is_ok()) return fail(s.message());
  int max_frames = 0;
  for (int i = 4; i < argc; ++i) {
    if (std::strcmp(argv[i], "--max-frames") == 0 && i + 1 < argc) {
      max_frames = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--set") == 0 && i + 1 < argc) {
      s = set_param(argv[++i], "--set", &params);
      if (!s.is_ok()) return fail(s.message());
    } else {
      return fail("unknown argument");
    }
  }
  params.map_threaded = true;  // the mapper on the second core
  params.loop.threaded = true;
  cv::setNumThreads(1);

  std::vector<StampedPose> ours, theirs, gt;
  std::vector<double> stamps;
  // The replay job's histogram of tracking times, and the same for OpenCV (large: on the heap).
  auto ours_ms = std::make_unique<LatencyStats>();
  auto opencv_ms = std::make_unique<LatencyStats>();
  if (!run_ours(sequence, params, max_frames, &ours, &stamps, ours_ms.get()))
    return fail("replay failed");
  if (!run_opencv(sequence, params, max_frames, &theirs, opencv_ms.get())) return 1;
  int bad = 0;
  s = read_tum_trajectory((sequence + "/groundtruth.txt").c_str(), &gt, &bad);
  if (!s.is_ok()) return fail(s.message());
  const EvaluationReport a = evaluate_all(gt, ours, &stamps);
  const EvaluationReport b = evaluate_all(gt, theirs, &stamps);
  const double ours_median = ours_ms->percentile_ms(0.5), ours_p95 = ours_ms->percentile_ms(0.95);
  const double cv_median = opencv_ms->percentile_ms(0.5);
  const double cv_p95 = opencv_ms->percentile_ms(0.95);
  std::printf("| system | frames | coverage | ATE cm (all frames) | median ms | p95 ms |\n");
  std::printf("|---|---|---|---|---|---|\n");
  std::printf("| rgbdtam | %zu | %.1f %% | %.2f | %.2f | %.2f |\n", stamps.size(),
              100.0 * a.coverage.fraction(), 100.0 * a.ate.rmse_m, ours_median, ours_p95);
  std::printf("| OpenCV RgbdOdometry %d.%d | %zu | %.1f %% | %.2f | %.2f | %.2f |\n",
              CV_VERSION_MAJOR, CV_VERSION_MINOR, stamps.size(), 100.0 * b.coverage.fraction(),
              100.0 * b.ate.rmse_m, cv_median, cv_p95);
  std::printf("ratio of medians (rgbdtam / OpenCV): %.3f\n", ours_median / cv_median);
  return 0;
}

}  // namespace
}  // namespace rgbdtam

int main(int argc, char** argv) { return rgbdtam::run(argc, argv); }

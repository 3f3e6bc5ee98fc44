// The soak: `rgbdtam run` on the host-emulation board with a V4L2 camera (a fake playing the
// committed clip in a loop, in real time) that is unplugged and plugged in again along the way.
// Prints resident memory as frames pass and checks that it stays flat after the first
// minutes, that every outage is recovered, and that the counters agree.
//   rgbdtam-soak [--frames N] [--fps HZ] [--outage-every-s S] [--outage-s S]
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "clip_camera.hpp"
#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/machine.hpp"
#include "rgbdtam/hal/tum_replay_source.hpp"
#include "run_job.hpp"

namespace {
double resident_mb() { return static_cast<double>(rgbdtam::resident_bytes()) / (1 << 20); }
}  // namespace

int main(int argc, char** argv) {
  using namespace rgbdtam;
  int frames = 100000;
  double fps = 60, outage_every_s = 300, outage_s = 2;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--frames")
      frames = std::atoi(argv[i + 1]);
    else if (a == "--fps")
      fps = std::atof(argv[i + 1]);
    else if (a == "--outage-every-s")
      outage_every_s = std::atof(argv[i + 1]);
    else if (a == "--outage-s")
      outage_s = std::atof(argv[i + 1]);
    else {
      std::fprintf(
          stderr,
          "usage: rgbdtam-soak [--frames N] [--fps HZ] [--outage-every-s S] [--outage-s S]\n");
      return 2;
    }
  }
  const std::string root = RGBDTAM_SOURCE_DIR;
  // The clip, decoded once.
  std::vector<std::vector<uint8_t>> gray;
  std::vector<std::vector<uint16_t>> depth;
  if (!testing::ClipCamera::load(root + "/data/tum_fr1_xyz_clip", &gray, &depth)) {
    std::fprintf(stderr, "soak: cannot read the clip\n");
    return 1;
  }
  std::vector<testing::ClipCamera::Outage> outages;
  const double duration_s = frames / fps * 1.5 + 60;
  for (double t = outage_every_s; t < duration_s; t += outage_every_s)
    outages.push_back({t, outage_s});
  testing::ClipCamera camera(gray, depth, 640, 480, fps, outages);

  const std::string board = root + "/board/host-emulation";
  const std::string fps_text = "sensor.fps=" + std::to_string(fps);
  RunOptions options;
  options.board_dir = board.c_str();
  options.board_overrides[0] = "sensor.kind=v4l2";
  options.board_overrides[1] = "sensor.device=/dev/soak-depth,/dev/soak-colour";
  options.board_overrides[2] = fps_text.c_str();
  options.board_override_count = 3;
  options.max_frames = frames;
  options.progress = false;
  options.v4l2_io = &camera;
  RunJob job;
  Status s = job.init(options);
  if (s.is_ok()) s = job.start();
  if (!s.is_ok()) {
    std::fprintf(stderr, "soak: %s\n", s.message());
    return 1;
  }
  const double init_mb = resident_mb();
  const int64_t t0 = monotonic_ns();
  std::printf(
      "| frames | minutes | resident MB | tracked | lost | resets | sensor errors | recoveries "
      "|\n");
  std::printf(
      "|--------|---------|-------------|---------|------|--------|---------------|------------|"
      "\n");
  auto row = [&](uint32_t n) {
    const FirmwareCounters& c = job.runtime().counters();
    std::printf("| %6u | %7.1f | %11.1f | %7u | %4u | %6u | %13u | %10u |\n", n,
                (monotonic_ns() - t0) * 1e-9 / 60, resident_mb(), c.tracked, c.lost,
                job.runtime().slam().tracking().counters().resets, c.sensor_errors,
                c.sensor_recoveries);
    std::fflush(stdout);
  };
  row(0);
  uint32_t next_row = 10000;
  double mb_at_10k = 0;
  while (job.step()) {
    const uint32_t n = job.runtime().counters().frames;
    if (n >= next_row) {
      if (next_row == 10000) mb_at_10k = resident_mb();
      row(n);
      next_row += 10000;
    }
  }
  job.finish();
  const FirmwareCounters& c = job.runtime().counters();
  const double end_mb = resident_mb();
  job.print_summary();
  const int outages_seen = camera.outages_started();
  std::printf("\nsoak: %u frames in %.1f min; camera played %llu, %d outages of %.1f s\n", c.frames,
              (monotonic_ns() - t0) * 1e-9 / 60,
              static_cast<unsigned long long>(camera.frames_played()), outages_seen, outage_s);
  std::printf("resident: %.1f MB after init, %.1f MB at 10 000 frames, %.1f MB at the end\n",
              init_mb, mb_at_10k, end_mb);
  bool ok = true;
  auto expect = [&](bool cond, const char* what) {
    std::printf("%s: %s\n", cond ? "ok" : "FAILED", what);
    ok = ok && cond;
  };
  expect(c.frames == static_cast<uint32_t>(frames), "every requested frame went through run");
  expect(end_mb - mb_at_10k < 2.0, "resident memory flat after 10 000 frames (within 2 MB)");
  expect(static_cast<int>(c.sensor_recoveries) == outages_seen, "every outage recovered");
  expect(c.tracked + c.lost + (c.frames - c.tracked - c.lost) == c.frames &&
             job.runtime().link().counters().odometry_sent +
                     job.runtime().link().counters().odometry_rate_limited +
                     job.runtime().link().counters().odometry_refused +
                     job.runtime().link().queue_drops() ==
                 c.frames,
         "every frame's ODOMETRY accounted for (sent, rate-limited, refused or dropped)");
  return ok ? 0 : 1;
}

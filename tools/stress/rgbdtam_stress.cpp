// Stress variants of TUM RGB-D sequences (tools/synthetic/stress_variants.hpp), for
// tools/robustness.sh.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "repeated_scene.hpp"
#include "stress_variants.hpp"

namespace {
int usage() {
  std::fprintf(stderr,
               "usage:\n"
               "  rgbdtam-stress decimate <in> <out> <n>\n"
               "  rgbdtam-stress cut <in> <out> <first> <count>\n"
               "  rgbdtam-stress kidnap <in> <out> <frame> <from-frame>\n"
               "  rgbdtam-stress blur <in> <out> --config <file> --exposure-ms <ms>\n"
               "  rgbdtam-stress drop-depth <in> <out> (--every <n> | --burst <length>/<period>)\n"
               "  rgbdtam-stress noise <in> <out> --config <file> --kind depth|colour|both\n"
               "                [--seed <n>]\n"
               "  rgbdtam-stress there-and-back <in> <out> --config <file>\n"
               "  rgbdtam-stress unregister <in> <out> --config <file> [--focal-scale <f>]\n"
               "                [--baseline-m <m>] [--depth-size <w>x<h>]\n"
               "  rgbdtam-stress dither <in> <out> --config <file> [--seed <n>]\n"
               "  rgbdtam-stress sensor-noise <in> <out> --config <file> [--seed <n>]\n"
               "                [--block-px <n>]\n"
               "  rgbdtam-stress two-camera <out> [--frames <n>] [--focal-scale <f>]\n"
               "                [--baseline-m <m>] [--depth-size <w>x<h>]\n"
               "  rgbdtam-stress pan <out> --peak-deg-s <deg/s> [--frames <n>] [--fps <hz>]\n"
               "                [--depth-late-ms <ms>] [--readout-ms <ms>]\n"
               "  rgbdtam-stress degenerate <out> --scene corridor|room [--frames <n>]\n"
               "  rgbdtam-stress wall <out> --distance-m <m> --yaw-deg <deg> [--frames <n>]\n"
               "  rgbdtam-stress concat <first> <second> <out> [--gap-s <s>]\n"
               "  rgbdtam-stress wander <in> <out> --config <file> [--frames <n>] [--seed <n>]\n"
               "  rgbdtam-stress repeated <out> --scene <name> [--frames <n>]\n"
               "  rgbdtam-stress repeated --list\n");
  return 2;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace rgbdtam::testing;
  if (argc < 3) return usage();
  const std::string verb = argv[1];
  if (verb == "repeated" && std::string(argv[2]) == "--list") {
    for (const RepeatedScene& s : RepeatedScene::family()) std::printf("%s\n", s.name.c_str());
    return 0;
  }
  const char* config = nullptr;
  std::string kind, scene;
  unsigned seed = 1;
  double exposure_ms = 0, peak = 0, fps = 30, gap_s = 1.0, distance_m = 0, yaw_deg = 0;
  double depth_late_ms = 0;
  double readout_ms = 0;
  DepthCameraShape depth_camera;
  int every = 0, burst = 0, period = 0, frames = -1, block_px = 1;
  std::vector<std::string> positional;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--config" && has) {
      config = argv[++i];
    } else if (a == "--exposure-ms" && has) {
      exposure_ms = std::atof(argv[++i]);
    } else if (a == "--gap-s" && has) {
      gap_s = std::atof(argv[++i]);
    } else if (a == "--scene" && has) {
      scene = argv[++i];
    } else if (a == "--kind" && has) {
      kind = argv[++i];
    } else if (a == "--seed" && has) {
      seed = static_cast<unsigned>(std::strtoul(argv[++i], nullptr, 10));
    } else if (a == "--block-px" && has) {
      block_px = std::atoi(argv[++i]);
    } else if (a == "--every" && has) {
      every = std::atoi(argv[++i]);
    } else if (a == "--burst" && has) {
      if (std::sscanf(argv[++i], "%d/%d", &burst, &period) != 2) return usage();
    } else if (a == "--peak-deg-s" && has) {
      peak = std::atof(argv[++i]);
    } else if (a == "--distance-m" && has) {
      distance_m = std::atof(argv[++i]);
    } else if (a == "--focal-scale" && has) {
      depth_camera.focal_scale = std::atof(argv[++i]);
    } else if (a == "--baseline-m" && has) {
      depth_camera.baseline_m = std::atof(argv[++i]);
    } else if (a == "--depth-size" && has) {
      if (std::sscanf(argv[++i], "%dx%d", &depth_camera.width_px, &depth_camera.height_px) != 2) {
        return usage();
      }
    } else if (a == "--yaw-deg" && has) {
      yaw_deg = std::atof(argv[++i]);
    } else if (a == "--frames" && has) {
      frames = std::atoi(argv[++i]);
    } else if (a == "--depth-late-ms" && has) {
      depth_late_ms = std::atof(argv[++i]);
    } else if (a == "--readout-ms" && has) {
      readout_ms = std::atof(argv[++i]);
    } else if (a == "--fps" && has) {
      fps = std::atof(argv[++i]);
    } else if (a.rfind("--", 0) == 0) {
      return usage();
    } else {
      positional.push_back(a);
    }
  }
  // Each verb's own length unless --frames gives one.
  const auto frames_or = [&frames](int fallback) { return frames < 0 ? fallback : frames; };
  bool ok;
  if (verb == "decimate" && positional.size() == 3) {
    ok = decimate_sequence(positional[0], positional[1], std::atoi(positional[2].c_str()));
  } else if (verb == "cut" && positional.size() == 4) {
    ok = cut_frames(positional[0], positional[1], std::atoi(positional[2].c_str()),
                    std::atoi(positional[3].c_str()));
  } else if (verb == "kidnap" && positional.size() == 4) {
    ok = kidnap_frame(positional[0], positional[1], std::atoi(positional[2].c_str()),
                      std::atoi(positional[3].c_str()));
  } else if (verb == "blur" && positional.size() == 2 && config != nullptr) {
    ok = blur_sequence(positional[0], positional[1], config, exposure_ms);
  } else if (verb == "drop-depth" && positional.size() == 2) {
    ok = drop_depth_frames(positional[0], positional[1], every, burst, period);
  } else if (verb == "noise" && positional.size() == 2 && config != nullptr) {
    ok = noise_sequence(positional[0], positional[1], config, kind, seed);
  } else if (verb == "there-and-back" && positional.size() == 2 && config != nullptr) {
    ok = there_and_back(positional[0], positional[1], config);
  } else if (verb == "unregister" && positional.size() == 2 && config != nullptr) {
    ok = unregister_depth(positional[0], positional[1], config, depth_camera);
  } else if (verb == "dither" && positional.size() == 2 && config != nullptr) {
    ok = dither_depth(positional[0], positional[1], config, seed);
  } else if (verb == "sensor-noise" && positional.size() == 2 && config != nullptr) {
    ok = sensor_noise_depth(positional[0], positional[1], config, seed, block_px);
  } else if (verb == "concat" && positional.size() == 3) {
    ok = concatenate(positional[0], positional[1], positional[2], gap_s);
  } else if (verb == "wander" && positional.size() == 2 && config != nullptr) {
    ok = wander_sequence(positional[0], positional[1], config, frames_or(150), seed);
  } else if (verb == "degenerate" && positional.size() == 1) {
    ok = degenerate_sequence(positional[0], scene, frames_or(150));
  } else if (verb == "wall" && positional.size() == 1) {
    ok = wall_sequence(positional[0], distance_m, yaw_deg, frames_or(150));
  } else if (verb == "repeated" && positional.size() == 1) {
    RepeatedScene s;
    frames = frames_or(150);
    ok = RepeatedScene::named(scene, &s) && frames >= 2;
    if (!ok) std::fprintf(stderr, "repeated: no scene '%s' (--list names them)\n", scene.c_str());
    ok = ok && repeated_sequence(positional[0], s, frames);
  } else if (verb == "two-camera" && positional.size() == 1) {
    ok = two_camera_sequence(positional[0], frames_or(kTwoCameraFrames), depth_camera);
  } else if (verb == "pan" && positional.size() == 1) {
    ok = pan_sequence(positional[0], peak, frames_or(150), fps, depth_late_ms, readout_ms);
  } else {
    return usage();
  }
  return ok ? 0 : 1;
}

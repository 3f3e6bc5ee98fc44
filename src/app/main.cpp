// rgbdtam command line: replay a recorded sequence, evaluate a trajectory, show parameters.

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "build_id.h"
#include "config_files.hpp"
#include "evaluate_command.hpp"
#include "map_command.hpp"
#include "output_guard.hpp"
#include "record_job.hpp"
#include "replay_job.hpp"
#include "rgbdtam/hal/fakenect_dump.hpp"
#include "rgbdtam/hal/file.hpp"
#include "rgbdtam/hal/ply_map_writer.hpp"
#include "run_job.hpp"
#include "vocabulary_command.hpp"

namespace rgbdtam {
namespace {

constexpr const char* kWrittenBy =
    "rgbdtam " RGBDTAM_VERSION ", commit " RGBDTAM_COMMIT ", board " RGBDTAM_BUILD_BOARD;

void usage() {
  std::fprintf(
      stderr,
      "usage:\n"
      "  rgbdtam replay <sequence-dir> --config <file> [--trajectory out.txt]\n"
      "                 [--final-trajectory out.txt] [--covariance out.txt] [--map map.ply]\n"
      "                 [--map-in saved.map] [--map-out saved.map]\n"
      "                 [--set key=value]... [--max-frames N] [--paced] [--trace out.csv]\n"
      "                 [--quiet] [--json]\n"
      "  rgbdtam eval <groundtruth.txt> <estimate.txt> [--json] [--frames rgb.txt]\n"
      "               [--plot out.svg] [--covariance est.cov]\n"
      "  rgbdtam params --config <file> [--set key=value]... [--markdown]\n"
      "  rgbdtam params --board <board-folder> [--board-set key=value]... [--set key=value]...\n"
      "  rgbdtam params --defaults [--markdown]\n"
      "  rgbdtam run --board <board-folder> [--board-set key=value]...\n"
      "              [--set key=value]... [--max-frames N] [--quiet]\n"
      "  rgbdtam check --board <board-folder> [--board-set key=value]... [--set key=value]...\n"
      "  rgbdtam record --board <board-folder> <out-dir> [--board-set key=value]...\n"
      "                 [--max-frames N]\n"
      "  rgbdtam map info <file>\n"
      "  rgbdtam map export <file> --grid <prefix> [--png] [--resolution m]\n"
      "                     [--heights low,high] [--max-range m] [--board <folder> | --up x,y,z]\n"
      "  rgbdtam vocabulary train <sequence-dir>... --config <file> --out <file>\n"
      "  rgbdtam --version\n"
      "sensor backends in this build: " RGBDTAM_HAL_BACKENDS "\n");
}

// --max-frames: a whole number of frames, 0 for all. False (with the message) for anything else.
bool parse_max_frames(const char* text, const char* verb, int* out) {
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || errno != 0 || v < 0 || v > INT_MAX) {
    std::fprintf(stderr, "rgbdtam %s: --max-frames needs a whole number of frames, got '%s'\n",
                 verb, text);
    return false;
  }
  *out = static_cast<int>(v);
  return true;
}

// Shared by replay and params: --config and --set build the parameters.
struct ConfigArgs {
  const char* config = nullptr;
  const char* overrides[64];
  int override_count = 0;
};

bool take_config_arg(int argc, char** argv, int* i, ConfigArgs* c) {
  if (std::strcmp(argv[*i], "--config") == 0 && *i + 1 < argc) {
    c->config = argv[++*i];
    return true;
  }
  if (std::strcmp(argv[*i], "--set") == 0 && *i + 1 < argc && c->override_count < 64) {
    c->overrides[c->override_count++] = argv[++*i];
    return true;
  }
  return false;
}

Status load_params(const ConfigArgs& c, Params* p) {
  if (c.config == nullptr) {
    return Status::error(StatusCode::kInvalidArgument, "--config <file> is required");
  }
  RGBDTAM_RETURN_IF_ERROR(read_params_file(c.config, p));
  for (int i = 0; i < c.override_count; ++i) {
    RGBDTAM_RETURN_IF_ERROR(set_param(c.overrides[i], "--set", p));
  }
  return Status::ok();
}

// --config: that file's values; --board: the board's keys, then its params file's values as
// it runs them; --defaults: every key's default (the schema, as docs/configuration.md lists it).
int params_command(int argc, char** argv) {
  ConfigArgs c;
  RunOptions board_options;
  KeyListing listing = KeyListing::kFile;
  bool defaults = false;
  for (int i = 0; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (std::strcmp(argv[i], "--markdown") == 0) {
      listing = KeyListing::kMarkdown;
    } else if (std::strcmp(argv[i], "--defaults") == 0) {
      defaults = true;
    } else if (std::strcmp(argv[i], "--board") == 0 && has_value) {
      board_options.board_dir = argv[++i];
    } else if (std::strcmp(argv[i], "--board-set") == 0 && has_value &&
               board_options.board_override_count < RunOptions::kMaxOverrides) {
      board_options.board_overrides[board_options.board_override_count++] = argv[++i];
    } else if (!take_config_arg(argc, argv, &i, &c)) {
      std::fprintf(stderr, "rgbdtam params: unknown argument '%s'\n", argv[i]);
      return 2;
    }
  }
  Board board;
  Params p;
  Status s;
  if (c.override_count > RunOptions::kMaxOverrides) {
    s = Status::error(StatusCode::kInvalidArgument, "more than %d --set",
                      RunOptions::kMaxOverrides);
  } else if (board_options.board_dir != nullptr) {
    for (int i = 0; i < c.override_count; ++i) {
      board_options.param_overrides[board_options.param_override_count++] = c.overrides[i];
    }
    s = c.config == nullptr ? load_board_and_params(board_options, &board, &p)
                            : Status::error(StatusCode::kInvalidArgument,
                                            "--board names its params file: no --config with it");
  } else if (!defaults) {
    s = load_params(c, &p);
  }
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam params: %s\n", s.message());
    return 1;
  }
  static char buf[32768];
  if (defaults || board_options.board_dir != nullptr) {
    print_board(board, buf, sizeof(buf), listing);
    std::printf("%s%s", buf, listing == KeyListing::kMarkdown ? "\n" : "");
  }
  print_params(p, buf, sizeof(buf), listing);
  std::fputs(buf, stdout);
  return 0;
}

// Ctrl-C, a kill and a dropped SSH session alike end a job after the current frame, with every
// output complete; one that comes during init ends the job as soon as it starts. Each job's
// request_stop is an atomic store: signal-safe. A job so ended exits 130 (as a shell reports
// Ctrl-C), whichever the signal, so that a script can tell it from a finished one.
volatile std::sig_atomic_t g_stop_requested = 0;
ReplayJob* g_replaying = nullptr;
RunJob* g_running = nullptr;
RecordJob* g_recording = nullptr;
void on_stop_signal(int) {
  g_stop_requested = 1;
  if (g_replaying != nullptr) g_replaying->request_stop();
  if (g_running != nullptr) g_running->request_stop();
  if (g_recording != nullptr) g_recording->request_stop();
}

constexpr int kInterruptedExitCode = 130;

// Makes `job` the one a signal stops, and stops it at once if a signal came before.
template <typename Job>
void stop_on_signal(Job* job, Job** slot) {
  *slot = job;
  if (g_stop_requested) job->request_stop();
}

int replay_command(int argc, char** argv) {
  ConfigArgs c;
  ReplayOptions options;
  bool json = false;  // one JSON object on stdout instead of the human summary
  const char* map_path = nullptr;
  for (int i = 0; i < argc; ++i) {
    if (take_config_arg(argc, argv, &i, &c)) continue;
    if (std::strcmp(argv[i], "--trajectory") == 0 && i + 1 < argc) {
      options.trajectory_path = argv[++i];
    } else if (std::strcmp(argv[i], "--final-trajectory") == 0 && i + 1 < argc) {
      options.final_trajectory_path = argv[++i];
    } else if (std::strcmp(argv[i], "--covariance") == 0 && i + 1 < argc) {
      options.covariance_path = argv[++i];
    } else if (std::strcmp(argv[i], "--map") == 0 && i + 1 < argc) {
      map_path = argv[++i];
    } else if (std::strcmp(argv[i], "--map-in") == 0 && i + 1 < argc) {
      options.map_in_path = argv[++i];
    } else if (std::strcmp(argv[i], "--map-out") == 0 && i + 1 < argc) {
      options.map_out_path = argv[++i];
    } else if (std::strcmp(argv[i], "--max-frames") == 0 && i + 1 < argc) {
      if (!parse_max_frames(argv[++i], "replay", &options.max_frames)) return 2;
    } else if (std::strcmp(argv[i], "--trace") == 0 && i + 1 < argc) {
      options.trace_path = argv[++i];
    } else if (std::strcmp(argv[i], "--paced") == 0) {
      options.paced = true;
    } else if (std::strcmp(argv[i], "--quiet") == 0) {
      options.progress = false;
    } else if (std::strcmp(argv[i], "--json") == 0) {
      json = true;
      options.progress = false;
    } else if (argv[i][0] != '-' && options.sequence == nullptr) {
      options.sequence = argv[i];
    } else {
      std::fprintf(stderr, "rgbdtam replay: unknown argument '%s'\n", argv[i]);
      usage();
      return 2;
    }
  }
  if (options.sequence == nullptr) {
    usage();
    return 2;
  }
  Status s = load_params(c, &options.params);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam replay: %s\n", s.message());
    return 1;
  }
  std::vector<CommandFile> inputs = {
      {"--config", given_path(c.config)},
      {"loop.vocabulary", options.params.loop.enabled ? options.params.loop.vocabulary : ""},
      {"--map-in", given_path(options.map_in_path), "--map-out"}};
  std::vector<std::string> input_folders;
  add_sequence_inputs(options.sequence, &inputs, &input_folders);
  if (!outputs_are_safe("rgbdtam replay",
                        {{"--trajectory", given_path(options.trajectory_path)},
                         {"--final-trajectory", given_path(options.final_trajectory_path)},
                         {"--covariance", given_path(options.covariance_path)},
                         {"--map", given_path(map_path)},
                         {"--map-out", given_path(options.map_out_path)},
                         {"--trace", given_path(options.trace_path)}},
                        inputs, input_folders)) {
    return 2;
  }
  if (options.trace_path != nullptr &&
      (options.params.map_threaded || options.params.loop.threaded)) {
    std::fprintf(stderr,
                 "rgbdtam replay: --trace times each module alone, so it needs the synchronous "
                 "modes (map.threaded = false, loop.threaded = false)\n");
    return 2;
  }
  if (map_path != nullptr && !options.params.map_enabled) {
    std::fprintf(stderr, "rgbdtam replay: --map needs map.enabled = true\n");
    return 2;
  }
  if ((options.map_in_path != nullptr || options.map_out_path != nullptr) &&
      (!options.params.loop.enabled || options.params.loop.vocabulary[0] == '\0')) {
    std::fprintf(stderr,
                 "rgbdtam replay: --map-in and --map-out need loop closure (loop.enabled = true "
                 "and a loop.vocabulary)\n");
    return 2;
  }
  if (options.map_out_path != nullptr && options.params.map_mode == MapMode::kLocalise) {
    std::fprintf(stderr,
                 "rgbdtam replay: map.mode = localise never writes a map: drop --map-out\n");
    return 2;
  }
  options.written_by = kWrittenBy;
  auto ply = std::make_unique<PlyMapWriter>();
  if (map_path != nullptr) options.map_sink = ply.get();
  auto job = std::make_unique<ReplayJob>();
  s = job->init(options);
  // The map file is created only once the run can start: a run that fails at init leaves nothing.
  if (s.is_ok() && map_path != nullptr) s = ply->open(map_path);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam replay: %s\n", s.message());
    return 1;
  }
  stop_on_signal(job.get(), &g_replaying);
  while (job->step() && ply->status().is_ok()) {
  }
  s = job->finish();
  g_replaying = nullptr;
  if (!s.is_ok()) std::fprintf(stderr, "rgbdtam replay: %s\n", s.message());
  if (job->stopped_early()) {
    std::fprintf(stderr, "rgbdtam replay: interrupted after %d frames\n",
                 static_cast<int>(job->counters().frames));
  }
  if (map_path != nullptr) {
    const Status ps = ply->close();
    if (!ps.is_ok()) {
      std::fprintf(stderr, "rgbdtam replay: %s\n", ps.message());
      s = ps;
    } else if (!json) {
      std::printf("map: %s (%llu points)\n", map_path,
                  static_cast<unsigned long long>(ply->points()));
    }
  }
  job->print_warnings();  // on stderr, whatever stdout carries
  if (!json) {
    job->print_summary();
    if (options.trajectory_path != nullptr && s.is_ok()) {
      std::printf("trajectory: %s (%zu poses)\n", options.trajectory_path, job->estimates().size());
    }
  }
  // Evaluate against the sequence's own ground truth when it has one.
  const std::string gt_path = std::string(options.sequence) + "/groundtruth.txt";
  std::vector<StampedPose> gt;
  int bad = 0;
  EvaluationReport report;
  if (read_tum_trajectory(gt_path.c_str(), &gt, &bad).is_ok()) {
    std::vector<double> stamps;
    for (int i = 0; i < job->source().rgb_list().size; ++i) {
      stamps.push_back(job->source().rgb_list().entries[i].timestamp_ns * 1e-9);
    }
    if (options.max_frames > 0 && static_cast<int>(stamps.size()) > options.max_frames) {
      stamps.resize(static_cast<size_t>(options.max_frames));
    }
    report = evaluate_all(gt, job->estimates(), &stamps);
    report.nees = evaluate_frame_to_frame_nees(gt, job->estimates(), job->covariances());
    if (!json) print_report(report, false, "all frames");
    if (!json && job->loop_enabled()) {
      // Offline figures: each frame on its keyframe as the final map places it.
      const EvaluationReport final_report = evaluate_all(gt, job->final_estimates(), &stamps);
      print_report(final_report, false, "final map, all frames");
    }
  }
  if (json) job->print_json(report);
  if (s.is_ok() && job->estimates().empty()) {
    std::fprintf(stderr, "rgbdtam replay: no frame was tracked, so there is no trajectory\n");
    return 1;
  }
  if (job->system().tracking().depth_units_wrong()) return 1;  // said in print_warnings()
  if (job->stopped_early()) return kInterruptedExitCode;
  return s.is_ok() ? 0 : 1;
}

// Options shared by run and record; positional arguments are left to the caller (null when
// there is none). False on an unknown argument.
bool parse_run_options(int argc, char** argv, RunOptions* options, const char** positional,
                       const char* verb) {
  for (int i = 0; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (std::strcmp(argv[i], "--board") == 0 && has_value) {
      options->board_dir = argv[++i];
    } else if (std::strcmp(argv[i], "--board-set") == 0 && has_value &&
               options->board_override_count < RunOptions::kMaxOverrides) {
      options->board_overrides[options->board_override_count++] = argv[++i];
    } else if (std::strcmp(argv[i], "--set") == 0 && has_value &&
               options->param_override_count < RunOptions::kMaxOverrides) {
      options->param_overrides[options->param_override_count++] = argv[++i];
    } else if (std::strcmp(argv[i], "--max-frames") == 0 && has_value) {
      if (!parse_max_frames(argv[++i], verb, &options->max_frames)) return false;
    } else if (std::strcmp(argv[i], "--quiet") == 0) {
      options->progress = false;
    } else if (positional != nullptr && *positional == nullptr && argv[i][0] != '-') {
      *positional = argv[i];
    } else {
      std::fprintf(stderr, "rgbdtam %s: unknown argument '%s'\n", verb, argv[i]);
      usage();
      return false;
    }
  }
  return true;
}

int run_command(int argc, char** argv) {
  RunOptions options;
  if (!parse_run_options(argc, argv, &options, nullptr, "run")) return 2;
  options.written_by = kWrittenBy;
  auto job = std::make_unique<RunJob>();
  Status s = job->init(options);
  if (s.is_ok()) s = job->start();
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam run: %s\n", s.message());
    return 1;
  }
  stop_on_signal(job.get(), &g_running);
  while (job->step()) {
  }
  job->finish();
  g_running = nullptr;
  job->print_summary();
  const Status saved = job->final_map_save();
  if (!saved.is_ok()) std::fprintf(stderr, "rgbdtam run: %s\n", saved.message());
  const bool none_tracked = job->runtime().counters().tracked == 0;
  if (none_tracked)
    std::fprintf(stderr, "rgbdtam run: no frame was tracked, so no pose was sent\n");
  if (!saved.is_ok()) return 1;
  if (g_stop_requested != 0) return kInterruptedExitCode;
  return none_tracked ? 1 : 0;
}

// A device named by a path (a replay folder, /dev/video0) exists; indices and URIs
// ("0", "default") are only known to the backend.
Status check_device_is_there(const Board& board) {
  const char* device = board.sensor_device;
  const bool folder = find_sensor_kind(board.sensor_kind)->device_is_a_folder;  // validated
  if (!folder && device[0] != '/') return Status::ok();
  struct stat st;
  if (::stat(device, &st) != 0) {
    return Status::error(StatusCode::kNotFound, "sensor.device %s: %s", device,
                         std::strerror(errno));
  }
  if (folder && !S_ISDIR(st.st_mode)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "sensor.device %s: not a folder (a %s sensor reads a recorded folder)",
                         device, board.sensor_kind);
  }
  // fakenect would end the process on a damaged dump: every entry is checked (run does too).
  if (std::strcmp(board.sensor_kind, "fakenect") == 0) {
    const Status dump = check_fakenect_dump(device);
    if (!dump.is_ok()) {
      return Status::error(dump.code(), "sensor.device: %s", dump.message());
    }
  }
  return Status::ok();
}

// What run checks before it opens anything, without opening the sensor: the board file and its
// overrides, the params file, and that this build has the board's sensor backend.
int check_command(int argc, char** argv) {
  RunOptions options;
  if (!parse_run_options(argc, argv, &options, nullptr, "check")) return 2;
  Board board;
  Params params;
  Status s = load_board_and_params(options, &board, &params);
  if (s.is_ok() && !sensor_backend_in_build(board.sensor_kind)) s = missing_backend_error(board);
  if (s.is_ok()) s = check_device_is_there(board);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam check: %s\n", s.message());
    return 1;
  }
  std::printf("board %s: sensor %s, in this build (backends: %s); link %s; %dx%d at %.0f Hz\n",
              board.name, board.sensor_kind, RGBDTAM_HAL_BACKENDS, board.link_kind,
              params.camera.width_px, params.camera.height_px, board.sensor_fps);
  return 0;
}

int record_command(int argc, char** argv) {
  RunOptions options;
  const char* out_dir = nullptr;
  if (!parse_run_options(argc, argv, &options, &out_dir, "record")) return 2;
  if (out_dir == nullptr) {
    usage();
    return 2;
  }
  auto job = std::make_unique<RecordJob>();
  Status s = job->init(options, out_dir);
  if (s.is_ok()) s = job->start();
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam record: %s\n", s.message());
    return 1;
  }
  stop_on_signal(job.get(), &g_recording);
  while (job->step()) {
  }
  s = job->finish();
  g_recording = nullptr;
  job->print_summary();
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam record: %s\n", s.message());
    return 1;
  }
  return g_stop_requested != 0 ? kInterruptedExitCode : 0;
}

}  // namespace
}  // namespace rgbdtam

int main(int argc, char** argv) {
  if (argc < 2) {
    rgbdtam::usage();
    return 2;
  }
  // Over a file-size limit a write fails with EFBIG, reported with the file's name as a full
  // disk is, instead of the process dying silently.
  std::signal(SIGXFSZ, SIG_IGN);
  const char* verb = argv[1];
  for (const char* job : {"replay", "run", "record"}) {
    if (std::strcmp(verb, job) != 0) continue;
    for (const int stop : {SIGINT, SIGTERM, SIGHUP}) std::signal(stop, rgbdtam::on_stop_signal);
  }
  if (std::strcmp(verb, "replay") == 0) return rgbdtam::replay_command(argc - 2, argv + 2);
  if (std::strcmp(verb, "eval") == 0) return rgbdtam::evaluate_command(argc - 2, argv + 2);
  if (std::strcmp(verb, "params") == 0) return rgbdtam::params_command(argc - 2, argv + 2);
  if (std::strcmp(verb, "run") == 0) return rgbdtam::run_command(argc - 2, argv + 2);
  if (std::strcmp(verb, "record") == 0) return rgbdtam::record_command(argc - 2, argv + 2);
  if (std::strcmp(verb, "check") == 0) return rgbdtam::check_command(argc - 2, argv + 2);
  if (std::strcmp(verb, "map") == 0) return rgbdtam::map_command(argc - 2, argv + 2);
  if (std::strcmp(verb, "vocabulary") == 0) {
    return rgbdtam::vocabulary_command(argc - 2, argv + 2);
  }
  if (std::strcmp(verb, "--version") == 0) {
    std::printf(
        "rgbdtam %s, commit %s, built for board %s; sensor backends: %s\n"
        "Licensed under the Apache License 2.0 (LICENSE); the libraries linked into it and "
        "their terms: NOTICE\n",
        RGBDTAM_VERSION, RGBDTAM_COMMIT, RGBDTAM_BUILD_BOARD, RGBDTAM_HAL_BACKENDS);
    return 0;
  }
  if (std::strcmp(verb, "--help") == 0 || std::strcmp(verb, "help") == 0) {
    rgbdtam::usage();
    return 0;
  }
  std::fprintf(stderr, "rgbdtam: unknown command '%s'\n", verb);
  rgbdtam::usage();
  return 2;
}

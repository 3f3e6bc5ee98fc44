// The rgbdtam command line as a user meets it: exit codes that say whether the job was done,
// outputs that never replace inputs, Ctrl-C that ends a replay with complete outputs, and
// write failures reported at once with the file and the reason.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fake_usb.hpp"
#include "stress_variants.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

struct Outcome {
  int exit_code = -1;
  std::string out, err;
};

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs `rgbdtam <args>` through the shell (after `wrapper`, a prefix command or shell
// statements), keeping stdout and stderr.
Outcome rgbdtam(const std::string& args, const std::string& wrapper = "") {
  const std::string dir = testing::make_temp_dir("cli_streams");
  const std::string command = wrapper + " " RGBDTAM_BINARY " " + args + " > " + dir +
                              "/stdout.txt 2> " + dir + "/stderr.txt";
  const int status = std::system(command.c_str());
  Outcome o;
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.out = read_all(dir + "/stdout.txt");
  o.err = read_all(dir + "/stderr.txt");
  return o;
}

std::string clip() { return testing::source_path("data/tum_fr1_xyz_clip"); }
std::string config() { return testing::source_path("config/tum_fr1.conf"); }

bool exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

TEST(Cli, TheMemoryBudgetChecksTheBoardsOwnPoolSize) {
  // raspberry-pi-4 keeps 24 keyframes (capacity.keyframe_pool), not the config's 32: over a
  // small budget, the refusal names the pool the firmware would allocate.
  const std::string board = testing::source_path("board/raspberry-pi-4");
  const Outcome o = rgbdtam("run --board " + board + " --board-set sensor.kind=replay" +
                            " --board-set sensor.usb_id= --board-set sensor.device=" + clip() +
                            " --board-set memory.budget_mb=64 --max-frames 1 --quiet");
  EXPECT_NE(o.exit_code, 0);
  EXPECT_NE(o.err.find("map.keyframe_pool 24 x"), std::string::npos) << o.err;
}

// Issue 35, items 20 and 21: eval refuses one stamp with two poses, skips (and counts) lines
// that are no pose, and counts a frame as estimated when a pose lies within the association
// window of it, as ATE associates.
TEST(Cli, EvalTakesStampsAsATEDoesAndRefusesOrSkipsWhatIsNoTrajectory) {
  const std::string dir = testing::make_temp_dir("cli_eval_inputs");
  std::vector<std::string> stamps;
  {
    std::ifstream list(clip() + "/rgb.txt");
    for (std::string line; std::getline(list, line);) {
      if (!line.empty() && line[0] != '#') stamps.push_back(line.substr(0, line.find(' ')));
    }
  }
  ASSERT_EQ(stamps.size(), 50u);
  auto estimate = [&](double shift_s, const std::string& extra) {
    std::string text;
    for (const std::string& t : stamps) {
      char line[96];
      std::snprintf(line, sizeof(line), "%.6f 0 0 0 0 0 0 1\n", std::atof(t.c_str()) + shift_s);
      text += line;
    }
    const std::string path = dir + "/est.txt";
    EXPECT_TRUE(testing::write_text(path, text + extra));
    return path;
  };
  const std::string gt = clip() + "/groundtruth.txt";
  const std::string frames = " --frames " + clip() + "/rgb.txt";
  for (const double shift_s : {0.0, 1e-6, 1e-3, 0.015}) {
    const Outcome o = rgbdtam("eval " + gt + " " + estimate(shift_s, "") + frames);
    EXPECT_EQ(o.exit_code, 0) << o.err;
    EXPECT_NE(o.out.find("coverage: 100.0 %"), std::string::npos) << shift_s << "\n" << o.out;
  }
  Outcome o = rgbdtam("eval " + gt + " " + estimate(0, stamps[3] + " 0.5 0 0 0 0 0 1\n") + frames);
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("stamp " + stamps[3] + " is listed twice with different poses"),
            std::string::npos)
      << o.err;
  o = rgbdtam("eval " + gt + " " +
              estimate(0, "1305031200.0 0 0 0 0 0 0 1000\n1305031201.0 1e300 0 0 0 0 0 1\n") +
              frames);
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.err.find("skipped 2 unreadable lines"), std::string::npos) << o.err;
  EXPECT_EQ(o.out.find("inf"), std::string::npos) << o.out;
}

TEST(Cli, EvalPlotsTheTrajectoryAsSvgAndNamesAPlotItCannotWrite) {
  const std::string dir = testing::make_temp_dir("cli_plot");
  const std::string gt = clip() + "/groundtruth.txt";
  // The ground truth against itself: every pose compared, none lost or false-valid.
  Outcome o = rgbdtam("eval " + gt + " " + gt + " --frames " + clip() + "/rgb.txt --plot " + dir +
                      "/plot.svg");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  const std::string svg = read_all(dir + "/plot.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("<g id=\"top-view\">"), std::string::npos);
  EXPECT_NE(svg.find("<g id=\"error-over-time\">"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_FALSE(exists(dir + "/plot.svg.partial"));
  o = rgbdtam("eval " + gt + " " + gt + " --plot " + dir + "/missing/plot.svg");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("--plot"), std::string::npos) << o.err;
}

TEST(Cli, AV4l2CameraFoundByUsbIdWithoutItsVideoNodesIsAClearError) {
  // A D435 attached, but uvcvideo has made no node for it (unbound, or still enumerating).
  const std::string sysfs = testing::make_temp_dir("cli_v4l2_usb");
  ASSERT_TRUE(testing::add_usb_device(sysfs, "2-1", "8086", "0b07", 2, 3));
  const std::string board =
      "--board " + testing::source_path("board/host-emulation") +
      " --board-set sensor.kind=v4l2 --board-set sensor.device=usb" +
      " --board-set sensor.usb_id=8086:0b07 --board-set board.sysfs_root=" + sysfs;
  const Outcome o = rgbdtam("run " + board + " --max-frames 1 --quiet");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("USB 8086:0b07 has no video node"), std::string::npos) << o.err;
}

#if RGBDTAM_WITH_FAKENECT
TEST(Cli, AFakenectFolderWithoutADumpIsAClearError) {
  // fakenect itself would end the process; the firmware checks the folder first.
  const Outcome o = rgbdtam("run --board " + testing::source_path("board/raspberry-pi-4") +
                            " --board-set sensor.kind=fakenect --board-set sensor.usb_id=" +
                            " --board-set sensor.device=" + clip() + " --max-frames 1 --quiet");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("is not a fakenect dump (no INDEX.txt)"), std::string::npos) << o.err;
}

TEST(Cli, ADamagedFakenectDumpIsNamedByCheckAndRunInsteadOfEndingTheProcess) {
  // fakenect prints its own line and exits on an entry naming a missing file.
  const std::string dump = testing::make_temp_dir("cli_fakenect_damaged");
  ASSERT_TRUE(testing::write_text(dump + "/INDEX.txt", "d-1.000000-1000-.pgm\n"));
  const std::string board = "--board " + testing::source_path("board/raspberry-pi-4") +
                            " --board-set sensor.kind=fakenect --board-set sensor.usb_id=" +
                            " --board-set sensor.device=" + dump;
  const std::string says = "INDEX.txt line 1: " + dump + "/d-1.000000-1000-.pgm is not a file";
  Outcome o = rgbdtam("run " + board + " --max-frames 1 --quiet");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find(says), std::string::npos) << o.err;
  EXPECT_EQ(o.out.find("Error: Cannot open file"), std::string::npos) << "fakenect never ran";
  o = rgbdtam("check " + board);
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find(says), std::string::npos) << o.err;
}
#endif

#if !RGBDTAM_WITH_OPENNI2
TEST(Cli, CheckRefusesABoardWhoseSensorThisBuildLacks) {
  const Outcome ok = rgbdtam("check --board " + testing::source_path("board/host-emulation"));
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  const Outcome o = rgbdtam("check --board " + testing::source_path("board/radxa-rock-5b"));
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(
      o.err.find("board 'radxa-rock-5b': this build has no 'openni2' sensor backend (it has:"),
      std::string::npos)
      << o.err;
}
#endif

TEST(Cli, ABadFrameCountIsAUsageError) {
  const Outcome o = rgbdtam("replay " + clip() + " --config " + config() + " --max-frames abc");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("--max-frames needs a whole number of frames, got 'abc'"), std::string::npos)
      << o.err;
}

TEST(Cli, AnOutputThatIsAnInputIsRefusedAndTheInputKept) {
  const std::string dir = testing::make_temp_dir("cli_inputs");
  ASSERT_EQ(std::system(("cp -r " + clip() + " " + dir + "/seq").c_str()), 0);
  const std::string gt = dir + "/seq/groundtruth.txt";
  const std::string before = read_all(gt);
  Outcome o = rgbdtam("replay " + dir + "/seq --config " + config() + " --trajectory " + gt);
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("is an input of this run"), std::string::npos) << o.err;
  EXPECT_EQ(read_all(gt), before);
  o = rgbdtam("replay " + dir + "/seq --config " + config() + " --map " + dir + "/seq/rgb.txt");
  EXPECT_EQ(o.exit_code, 2);
}

// Issue 35, items 7 to 9: every command checks its outputs against its inputs as replay does,
// refuses (exit 2) and keeps the input.
TEST(Cli, NoCommandWritesOverItsOwnInputs) {
  const std::string dir = testing::make_temp_dir("cli_no_command_replaces");
  ASSERT_EQ(std::system(("cp -r " + clip() + " " + dir + "/seq").c_str()), 0);
  const std::string seq = dir + "/seq";
  const std::string map = dir + "/m.yaml";  // a map named like a grid's output
  ASSERT_EQ(rgbdtam("replay " + seq + " --config " + config() +
                    " --quiet --max-frames 10 --map-out " + map)
                .exit_code,
            0);
  std::string image;
  {
    std::ifstream list(seq + "/rgb.txt");
    for (std::string line; std::getline(list, line) && image.empty();) {
      if (!line.empty() && line[0] != '#') image = seq + "/" + line.substr(line.find(' ') + 1);
    }
  }
  const struct {
    std::string command, kept;
  } cases[] = {
      {"vocabulary train " + seq + " --config " + config() + " --out " + seq + "/rgb.txt",
       seq + "/rgb.txt"},
      {"vocabulary train " + seq + " --config " + config() + " --out " + image, image},
      {"vocabulary train " + seq + " --config " + config() + " --out " + config(), config()},
      {"vocabulary train " + seq + " --config " + config() + " --out " +
           testing::source_path("data/vocabulary/tum-k10-l4.voc"),
       testing::source_path("data/vocabulary/tum-k10-l4.voc")},
      {"eval " + seq + "/groundtruth.txt " + seq + "/groundtruth.txt --plot " + seq +
           "/groundtruth.txt",
       seq + "/groundtruth.txt"},
      {"eval " + seq + "/groundtruth.txt " + seq + "/groundtruth.txt --frames " + seq +
           "/rgb.txt --plot " + seq + "/rgb.txt",
       seq + "/rgb.txt"},
      {"map export " + map + " --grid " + dir + "/m", map},
  };
  for (const auto& c : cases) {
    const std::string before = read_all(c.kept);
    const Outcome o = rgbdtam(c.command);
    EXPECT_EQ(o.exit_code, 2) << c.command << "\n" << o.err;
    EXPECT_TRUE(o.err.find("is an input of this run") != std::string::npos ||
                o.err.find("would replace one of the inputs in") != std::string::npos)
        << o.err;
    EXPECT_EQ(read_all(c.kept), before) << c.kept;
  }
#ifdef RGBDTAM_OCTOMAP_BINARY
  const std::string before = read_all(map);
  const std::string command = std::string(RGBDTAM_OCTOMAP_BINARY) + " " + map + " " + map +
                              " > /dev/null 2> " + dir + "/octomap.err";
  const int status = std::system(command.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_NE(read_all(dir + "/octomap.err")
                .find("rgbdtam-octomap: <out.bt> " + map + " is an input of this run"),
            std::string::npos);
  EXPECT_EQ(read_all(map), before);
#endif
}

// Issue 23, defect 1: the vocabulary is an input too.
TEST(Cli, AnOutputOverTheVocabularyIsRefusedAndTheVocabularyKept) {
  const std::string dir = testing::make_temp_dir("cli_vocabulary_input");
  const std::string voc = dir + "/words.voc";
  ASSERT_EQ(
      std::system(
          ("cp " + testing::source_path("data/vocabulary/tum-k10-l4.voc") + " " + voc).c_str()),
      0);
  const std::string before = read_all(voc);
  for (const char* option : {" --trajectory ", " --final-trajectory ", " --map "}) {
    const Outcome o = rgbdtam("replay " + clip() + " --config " + config() +
                              " --set loop.vocabulary=" + voc + option + voc);
    EXPECT_EQ(o.exit_code, 2) << option;
    EXPECT_NE(o.err.find("is an input of this run (" + voc + ")"), std::string::npos) << o.err;
  }
  EXPECT_EQ(read_all(voc), before);
}

// Issue 23, defect 6: two outputs on one path are refused before the run, and a run that fails
// at init creates no output.
TEST(Cli, TwoOutputsOnOnePathAreRefusedAndAFailedInitLeavesNoFile) {
  const std::string dir = testing::make_temp_dir("cli_one_path");
  Outcome o = rgbdtam("replay " + clip() + " --config " + config() + " --trajectory " + dir +
                      "/x --map " + dir + "/../" + dir.substr(dir.rfind('/') + 1) + "/x");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("--trajectory and --map name one file"), std::string::npos) << o.err;
  EXPECT_FALSE(exists(dir + "/x"));
  {
    std::ofstream bad(dir + "/bad.voc");
    bad << "RGBDVOC1 but not really";
  }
  o = rgbdtam("replay " + clip() + " --config " + config() + " --set loop.vocabulary=" + dir +
              "/bad.voc --trajectory " + dir + "/t.txt --map " + dir + "/m.ply");
  EXPECT_EQ(o.exit_code, 1);
  for (const char* name : {"/t.txt", "/t.txt.partial", "/m.ply", "/m.ply.partial"}) {
    EXPECT_FALSE(exists(dir + name)) << name;
  }
}

// Issue 20: a trace of each module's time per frame, for tools/task_sim.py.
TEST(Cli, ATraceHasAFrameALineAndNeedsTheSynchronousModes) {
  const std::string dir = testing::make_temp_dir("cli_trace");
  Outcome o = rgbdtam("replay " + clip() + " --config " + config() + " --trace " + dir +
                      "/trace.csv --quiet");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  std::ifstream in(dir + "/trace.csv");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line,
            "stamp_ns,sensor_ns,tracker_ns,keyframe,build_ns,mapper_items,mapper_ns,loop_items,"
            "loop_ns");
  int frames = 0, keyframes = 0;
  while (std::getline(in, line)) {
    ++frames;
    std::vector<std::string> fields(1);
    for (char c : line) {
      if (c == ',') {
        fields.emplace_back();
      } else {
        fields.back() += c;
      }
    }
    ASSERT_EQ(fields.size(), 9u) << line;
    keyframes += fields[3] == "1" ? 1 : 0;
  }
  EXPECT_EQ(frames, 50);
  EXPECT_GT(keyframes, 0);
  o = rgbdtam("replay " + clip() + " --config " + config() + " --set map.threaded=true --trace " +
              dir + "/threaded.csv");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("--trace times each module alone"), std::string::npos) << o.err;
  EXPECT_FALSE(exists(dir + "/threaded.csv"));
}

// Issue 23: the summary says what the place store forgot. Every frame of the clip a keyframe
// into a store of 8 places: 42 of 50 forgotten, and the run still right.
TEST(Cli, TheSummarySaysWhatThePlaceStoreForgot) {
  // The clip's first 20 frames, a keyframe each: the store wraps once and a half.
  const std::string first20 = testing::make_temp_dir("cli_place_store") + "/first20";
  ASSERT_TRUE(testing::cut_frames(clip(), first20, 20, 30));
  const Outcome o = rgbdtam("replay " + first20 + " --config " + config() +
                            " --set loop.places=8 --set tracker.keyframe_overlap=0.99" +
                            " --set map.reuse_candidates=0 --quiet");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("loop: 20 places (the store keeps 8; 12 forgotten)"), std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("coverage: 100.0 %"), std::string::npos) << o.out;
}

TEST(Cli, AMapFileIsDescribedAndExportedAsAGridForPlanners) {
  const std::string dir = testing::make_temp_dir("cli_map");
  const Outcome replay = rgbdtam("replay " + clip() + " --config " + config() +
                                 " --quiet --map-out " + dir + "/clip.map");
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_NE(replay.out.find("places saved in"), std::string::npos) << replay.out;
  const Outcome info = rgbdtam("map info " + dir + "/clip.map");
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("camera: 640x480"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("by rgbdtam "), std::string::npos) << info.out;

  const Outcome grid = rgbdtam("map export " + dir + "/clip.map --grid " + dir + "/clip --png");
  EXPECT_EQ(grid.exit_code, 0) << grid.err;
  EXPECT_NE(grid.out.find("level: assumed"), std::string::npos) << grid.out;
  EXPECT_EQ(read_all(dir + "/clip.pgm").substr(0, 3), "P5\n");
  EXPECT_NE(read_all(dir + "/clip.yaml").find("image: clip.pgm\n"), std::string::npos);
  EXPECT_EQ(read_all(dir + "/clip.png").substr(1, 3), "PNG");

  const Outcome no_grid = rgbdtam("map export " + dir + "/clip.map");
  EXPECT_EQ(no_grid.exit_code, 1);
  EXPECT_NE(no_grid.err.find("--grid <prefix> is required"), std::string::npos) << no_grid.err;
  const Outcome not_a_map = rgbdtam("map export " + config() + " --grid " + dir + "/x");
  EXPECT_EQ(not_a_map.exit_code, 1);
  EXPECT_NE(not_a_map.err.find("not an rgbdtam map file"), std::string::npos) << not_a_map.err;
  EXPECT_FALSE(exists(dir + "/x.pgm"));
  EXPECT_EQ(rgbdtam("map frobnicate").exit_code, 2);
}

// Issue 35: settings that could never be right are refused at start, each named.
std::string host_board() { return testing::source_path("board/host-emulation"); }

TEST(Cli, AMountingOffsetOfKilometresIsRefused) {
  for (const char* offset : {"1e300", "1e39", "11"}) {
    const Outcome o = rgbdtam("check --board " + host_board() +
                              " --board-set 'link.T_b_c=1 0 0 0 " + offset + " 0 0'");
    EXPECT_EQ(o.exit_code, 1) << offset;
    EXPECT_NE(o.err.find("key 'link.T_b_c': '1 0 0 0 " + std::string(offset) +
                         " 0 0' is not valid (body from camera: qw qx qy qz (unit) tx ty tz (m, "
                         "each within 10))"),
              std::string::npos)
        << o.err;
  }
  const Outcome metres =
      rgbdtam("check --board " + host_board() + " --board-set 'link.T_b_c=1 0 0 0 0.2 -0.05 9.5'");
  EXPECT_EQ(metres.exit_code, 0) << metres.err;
}

TEST(Cli, EveryTrackerLevelAtZeroIterationsIsRefusedButOneIsFine) {
  std::string all_zero;
  for (const char* level : {"l0", "l1", "l2", "l3"}) {
    all_zero += std::string(" --set tracker.iterations_") + level + "=0";
  }
  const Outcome o = rgbdtam("replay " + clip() + " --config " + config() + all_zero);
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("'tracker.iterations_l0'..'l3' are all 0"), std::string::npos) << o.err;
  const Outcome one = rgbdtam("replay " + clip() + " --config " + config() +
                              " --set tracker.iterations_l0=0 --max-frames 5 --quiet");
  EXPECT_EQ(one.exit_code, 0) << one.err;
}

// Issue 35, item 3: the clip (made at 5000 units per metre) read at 1000 sent 45 of 49 poses
// wrong; now none is sent but the first (the origin), and the error says which depth.factor fits.
TEST(Cli, DepthInOtherUnitsThanTheSensorsIsRefusedAndTheFittingFactorNamed) {
  const Outcome o =
      rgbdtam("replay " + clip() + " --config " + config() + " --set depth.factor=1000 --json");
  EXPECT_EQ(o.exit_code, 1) << "a run in the wrong units is a failed run";
  // The first frame is the world's origin, sent before a second to compare its depth with.
  EXPECT_NE(o.out.find("\"depth_units_off\": 49"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("\"tracked\": 1"), std::string::npos) << o.out;
  EXPECT_NE(o.err.find("not in the sensor's units"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("at depth.factor 49"), std::string::npos) << o.err;  // 4900-5100
  const Outcome right = rgbdtam("replay " + clip() + " --config " + config() + " --json");
  EXPECT_EQ(right.exit_code, 0) << right.err;
  EXPECT_NE(right.out.find("\"depth_units_off\": 0"), std::string::npos) << right.out;
}

TEST(Cli, ANearestDepthOfZeroIsRefused) {
  const Outcome o = rgbdtam("replay " + clip() + " --config " + config() + " --set depth.min=0");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("'depth.min'"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("0.01"), std::string::npos) << o.err;
}

TEST(Cli, AnAltitudeWithoutItsLatitudeAndLongitudeIsRefused) {
  const Outcome o = rgbdtam("check --board " + host_board() + " --board-set origin.altitude_m=120");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("origin.altitude_m needs origin.latitude_deg and origin.longitude_deg"),
            std::string::npos)
      << o.err;
  const Outcome whole = rgbdtam("check --board " + host_board() +
                                " --board-set origin.altitude_m=120 --board-set "
                                "origin.latitude_deg=47.4 --board-set origin.longitude_deg=8.5");
  EXPECT_EQ(whole.exit_code, 0) << whole.err;
}

TEST(Cli, AnEmptyOrMissingDeviceOrConfigIsNamedByCheckAndRun) {
  for (const char* command : {"check", "run"}) {
    Outcome o = rgbdtam(std::string(command) + " --board " + host_board() +
                        " --board-set sensor.device= --quiet");
    EXPECT_EQ(o.exit_code, 1) << command;
    EXPECT_NE(o.err.find("sensor.device is empty: name the replay sensor"), std::string::npos)
        << o.err;
    o = rgbdtam(std::string(command) + " --board " + host_board() +
                " --board-set sensor.config= --quiet");
    EXPECT_EQ(o.exit_code, 1) << command;
    EXPECT_NE(o.err.find("sensor.config is empty"), std::string::npos) << o.err;
  }
  const Outcome missing =
      rgbdtam("check --board " + host_board() + " --board-set sensor.device=/nonexistent/sequence");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("sensor.device /nonexistent/sequence: No such file or directory"),
            std::string::npos)
      << missing.err;
  const Outcome file = rgbdtam("check --board " + host_board() +
                               " --board-set sensor.device=" + clip() + "/rgb.txt");
  EXPECT_EQ(file.exit_code, 1);
  EXPECT_NE(file.err.find("not a folder"), std::string::npos) << file.err;
}

// Issue 35, item 14: a board map that does not load ends run with its message; nothing ran,
// so nothing is saved over it.
TEST(Cli, ABoardMapThatFailsToLoadEndsRunWithItsMessageAndStaysAsItWas) {
  const std::string dir = testing::make_temp_dir("cli_board_map");
  ASSERT_TRUE(testing::write_text(dir + "/damaged.map", "RGBDTAM map, but not really\n"));
  ASSERT_EQ(::mkdir((dir + "/folder.map").c_str(), 0755), 0);
  const struct {
    std::string map, extra, message;
  } cases[] = {
      {dir + "/damaged.map", "", "damaged.map"},
      {config(), "", "not an rgbdtam map file"},
      {dir + "/folder.map", "", "folder.map"},
      {dir + "/damaged.map", " --set loop.enabled=false", "needs loop closure"},
  };
  for (const auto& c : cases) {
    const std::string before = read_all(c.map);
    const Outcome o = rgbdtam("run --board " + host_board() + " --board-set map.file=" + c.map +
                              c.extra + " --max-frames 5 --quiet");
    EXPECT_EQ(o.exit_code, 1) << c.map << c.extra << "\n" << o.err;
    EXPECT_NE(o.err.find(c.message), std::string::npos) << o.err;
    EXPECT_EQ(o.err.find("assertion failed"), std::string::npos) << o.err;
    EXPECT_EQ(read_all(c.map), before);
  }
}

// Issue 23, defect 3: validation knows the smallest image every component takes.
TEST(Cli, ACameraTooSmallIsRefusedWithItsMinimum) {
  const Outcome o = rgbdtam("replay " + clip() + " --config " + config() + " --set camera.width=8");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("must be at least 40 px"), std::string::npos) << o.err;
  EXPECT_EQ(o.err.find("assertion failed"), std::string::npos) << o.err;
}

// Issue 23, defect 5: over a file-size limit the write fails with the file's name.
TEST(Cli, AFileSizeLimitIsAClearErrorNotASilentDeath) {
  const std::string dir = testing::make_temp_dir("cli_ulimit");
  const Outcome o =
      rgbdtam("replay " + clip() + " --config " + config() + " --map " + dir + "/m.ply --quiet",
              "ulimit -f 16;");
  EXPECT_EQ(o.exit_code, 1) << o.err;
  EXPECT_NE(o.err.find("m.ply.partial: write failed: File too large"), std::string::npos) << o.err;
  EXPECT_FALSE(exists(dir + "/m.ply.partial")) << "issue 35, item 11: nothing left behind";
}

// Issue 35, items 11 and 12: an output written at the end is checked at the start, and a
// failed write leaves no .partial file.
TEST(Cli, AnOutputWrittenAtTheEndIsCheckedAtTheStartAndAFailureLeavesNothing) {
  const std::string dir = testing::make_temp_dir("cli_end_outputs");
  for (const char* option : {"--map-out", "--final-trajectory"}) {
    Outcome o = rgbdtam("replay " + clip() + " --config " + config() + " " + option + " " + dir);
    EXPECT_EQ(o.exit_code, 1) << option;
    EXPECT_NE(o.err.find(dir + ": is a folder, not a file"), std::string::npos) << o.err;
    EXPECT_EQ(o.out.find("frames: read"), std::string::npos) << "refused before the replay";
    o = rgbdtam("replay " + clip() + " --config " + config() + " " + option + " " + dir +
                "/missing/x");
    EXPECT_EQ(o.exit_code, 1) << option;
    EXPECT_NE(o.err.find("/missing/x.partial: cannot create: No such file or directory"),
              std::string::npos)
        << o.err;
  }
  const Outcome full = rgbdtam("replay " + clip() + " --config " + config() +
                                   " --quiet --max-frames 10 --map-out " + dir + "/m.map",
                               "ulimit -f 16;");
  EXPECT_EQ(full.exit_code, 1) << full.err;
  EXPECT_NE(full.err.find("m.map.partial: write failed: File too large"), std::string::npos)
      << full.err;
  EXPECT_FALSE(exists(dir + "/m.map.partial"));
  EXPECT_FALSE(exists(dir + "/m.map"));
}

// Issue 35, items 10 and 13: a run whose final map save fails says so and what the file holds,
// and exits 1; a map is extended in place by naming it as input and output.
TEST(Cli, AFailedFinalMapSaveIsAFailedRunAndAMapIsExtendedInPlace) {
  const std::string dir = testing::make_temp_dir("cli_map_save");
  const Outcome run = rgbdtam("run --board " + host_board() + " --board-set map.file=" + dir +
                                  "/board.map --max-frames 20 --quiet",
                              "ulimit -f 16;");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("board.map was not saved at the end ("), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("File too large): it holds nothing from this run"), std::string::npos)
      << run.err;
  EXPECT_FALSE(exists(dir + "/board.map.partial"));

  const std::string map = dir + "/clip.map";
  Outcome o = rgbdtam("replay " + clip() + " --config " + config() +
                      " --quiet --max-frames 20 --map-out " + map);
  ASSERT_EQ(o.exit_code, 0) << o.err;
  o = rgbdtam("replay " + clip() + " --config " + config() + " --quiet --max-frames 20 --map-in " +
              map + " --map-out " + map);
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("places saved in"), std::string::npos) << o.out;
}

TEST(Cli, OutputsAppearWhenCompleteAndAFullDiskIsNamed) {
  const std::string dir = testing::make_temp_dir("cli_outputs");
  Outcome o = rgbdtam("replay " + clip() + " --config " + config() + " --trajectory " + dir +
                      "/t.txt --map " + dir + "/m.ply");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_TRUE(exists(dir + "/t.txt") && exists(dir + "/m.ply"));
  EXPECT_FALSE(exists(dir + "/t.txt.partial") || exists(dir + "/m.ply.partial"));
  o = rgbdtam("replay " + clip() + " --config " + config() + " --trajectory /dev/full");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("/dev/full: write failed: No space left on device"), std::string::npos)
      << o.err;
}

TEST(Cli, NoPoseAtAllIsAFailedRun) {
  const std::string dir = testing::make_temp_dir("cli_noise");
  ASSERT_TRUE(testing::noise_sequence(clip(), dir + "/noise", config(), "depth", 5));
  const Outcome o = rgbdtam("replay " + dir + "/noise --config " + config());
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("no frame was tracked"), std::string::npos) << o.err;
}

// Ctrl-C, a kill, and (issue 23, defect 4) a dropped SSH session's SIGHUP.
class CliStop : public ::testing::TestWithParam<const char*> {};

TEST_P(CliStop, EndsAReplayWithCompleteOutputs) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "no full fr1_xyz on this machine";
  const std::string dir = testing::make_temp_dir("cli_stop");
  // The signal comes once poses are on disk (the trajectory is flushed at least once a second),
  // however long init takes on a loaded machine.
  const std::string signal_when_tracking =
      "sh -c '\"$0\" \"$@\" & p=$!; i=0; while [ $i -lt 600 ] && [ \"$(cat " + dir +
      "/t.txt.partial 2>/dev/null | wc -l)\" -lt 3 ]; do sleep 0.1; i=$((i + 1)); done; kill -" +
      GetParam() + " $p; wait $p'";
  const Outcome o = rgbdtam("replay " + seq + " --config " + config() + " --trajectory " + dir +
                                "/t.txt --map " + dir + "/m.ply",
                            signal_when_tracking);
  EXPECT_EQ(o.exit_code, 130) << o.err;
  EXPECT_NE(o.err.find("interrupted after"), std::string::npos) << o.err;
  const std::string trajectory = read_all(dir + "/t.txt");
  int lines = 0;
  for (char c : trajectory) lines += c == '\n';
  EXPECT_GT(lines, 2) << "the poses up to the interruption";
  EXPECT_EQ(trajectory.back(), '\n') << "no half line";
  // The PLY's header counts exactly the vertices it holds.
  const std::string ply = read_all(dir + "/m.ply");
  const size_t count_at = ply.find("element vertex ");
  const size_t body_at = ply.find("end_header\n");
  ASSERT_NE(count_at, std::string::npos);
  ASSERT_NE(body_at, std::string::npos);
  const long long count = std::atoll(ply.c_str() + count_at + 15);
  EXPECT_EQ(static_cast<long long>(ply.size() - body_at - 11), count * 15);
}

TEST_P(CliStop, EndsRunAndRecordWithTheirSummaries) {
  const std::string seq = testing::full_fr1_xyz();
  if (seq.empty()) GTEST_SKIP() << "no full fr1_xyz on this machine";
  // The board plays the sequence at 30 Hz: 26 s, so the signal comes while it runs.
  const std::string board =
      testing::source_path("board/host-emulation") + " --board-set sensor.device=" + seq;
  const std::string wrapper = std::string("timeout --preserve-status -s ") + GetParam() + " 3";
  // Issue 35, item 22: interrupted, as replay says it (exit 130), with the summary printed.
  const Outcome run = rgbdtam("run --board " + board + " --quiet", wrapper);
  EXPECT_EQ(run.exit_code, 130) << run.err;
  EXPECT_NE(run.out.find("frames: "), std::string::npos) << run.out;
  // Issue 23, defect 8: no word of withheld outage messages when there was no outage.
  EXPECT_EQ(run.out.find("not posted"), std::string::npos) << run.out;
  const std::string dir = testing::make_temp_dir("cli_stop_record");
  const Outcome record = rgbdtam("record --board " + board + " " + dir + "/rec", wrapper);
  EXPECT_EQ(record.exit_code, 130) << record.err;
  EXPECT_TRUE(exists(dir + "/rec/rgb.txt") && exists(dir + "/rec/depth.txt")) << record.err;
  EXPECT_FALSE(exists(dir + "/rec/rgb.txt.partial")) << record.err;
}

INSTANTIATE_TEST_SUITE_P(Signals, CliStop, ::testing::Values("INT", "TERM", "HUP"));

TEST(Cli, TrainingAVocabularyTwiceGivesTheSameFile) {
  const std::string dir = testing::make_temp_dir("cli_vocabulary");
  for (const char* name : {"/a.voc", "/b.voc"}) {
    const Outcome o = rgbdtam("vocabulary train " + clip() + " --config " + config() +
                              " --every 5 --depth 3 --out " + dir + name);
    ASSERT_EQ(o.exit_code, 0) << o.err;
  }
  const std::string a = read_all(dir + "/a.voc");
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, read_all(dir + "/b.voc"));
  // The trained file is one a replay can use.
  const Outcome o = rgbdtam("replay " + clip() + " --config " + config() +
                            " --set loop.vocabulary=" + dir + "/a.voc --max-frames 5");
  EXPECT_EQ(o.exit_code, 0) << o.err;
}

TEST(Cli, VocabularyProblemsAreClearErrors) {
  Outcome o = rgbdtam("vocabulary train " + clip() + " --config " + config());
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("needs at least one sequence, --config and --out"), std::string::npos)
      << o.err;
  o = rgbdtam("vocabulary train " + clip() + " --config " + config() + " --depth 0 --out x");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("--depth needs 1 to 8"), std::string::npos) << o.err;
  const std::string dir = testing::make_temp_dir("cli_bad_vocabulary");
  {
    std::ofstream bad(dir + "/bad.voc");
    bad << "RGBDVOC1 but not really";
  }
  o = rgbdtam("replay " + clip() + " --config " + config() + " --set loop.vocabulary=" + dir +
              "/bad.voc");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("bad.voc"), std::string::npos) << o.err;
  o = rgbdtam("replay " + clip() + " --config " + config() + " --set loop.vocabulary=" + dir +
              "/missing.voc");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.err.find("missing.voc: cannot open"), std::string::npos) << o.err;
  // A config that names none runs without loop closure, and says so.
  o = rgbdtam("replay " + clip() + " --config " + config() +
              " --set loop.vocabulary= --max-frames 3");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.err.find("no loop closure or relocalisation"), std::string::npos) << o.err;
}

}  // namespace
}  // namespace rgbdtam

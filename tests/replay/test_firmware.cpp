// rgbdtam run on the host-emulation board, end to end: the committed clip at its recorded
// rate, MAVLink over UDP to this test acting as the monitor. Every frame's ODOMETRY arrives
// intact, the received trajectory is as accurate as replay's, the frame trigger pulses once
// per frame, and sensor errors reach the operator as STATUSTEXT and a fault blink.
#include <fcntl.h>
#include <gtest/gtest.h>

#include <pty.h>
#include <unistd.h>
#include <memory>

#include <atomic>
#include <chrono>
#include <thread>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "evaluate_command.hpp"
#include "firmware_monitor.hpp"
#include "replay_runner.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/hal/udp_link.hpp"
#include "run_job.hpp"
#include "test_paths.hpp"
#include "tum_writer.hpp"

namespace rgbdtam {
namespace {

// The host-emulation board on a synthetic sequence written into dir (with dir/camera.conf).
// every_frame: the replay holds each frame for the tracker (testing::run_board).
void run_synthetic_at_10_hz(testing::Monitor* monitor, RunJob* job, const std::string& dir,
                            bool every_frame = false) {
  testing::run_board(
      monitor, job,
      {"sensor.device=" + dir, "sensor.config=" + dir + "/camera.conf", "sensor.fps=10"}, "",
      every_frame);
}

TEST(Firmware, HostEmulationStreamsEveryPoseAndMatchesReplay) {
  testing::Monitor monitor;
  RunJob job;
  testing::run_board(&monitor, &job, {});
  const FirmwareCounters& c = job.runtime().counters();
  EXPECT_EQ(c.frames + job.sensor_dropped(), 50u);
  EXPECT_EQ(monitor.odometry, static_cast<int>(c.frames));
  EXPECT_EQ(static_cast<int>(monitor.poses.size()), static_cast<int>(c.tracked));
  EXPECT_EQ(monitor.decoder.counters().crc_errors, 0u);
  EXPECT_EQ(monitor.decoder.counters().lost_frames, 0u);
  EXPECT_GE(monitor.heartbeats, 1);
  // One trigger pulse per tracked frame on the fake chip.
  const auto* gpio = static_cast<const FakeGpio*>(job.gpio());
  ASSERT_NE(gpio, nullptr);
  EXPECT_EQ(gpio->rising_edges(job.board().gpio_trigger_line), c.frames);
  // The LED showed every frame's state: tracking for each tracked frame, not for the others.
  const StatusLed& led = job.runtime().led();
  EXPECT_EQ(led.updates_in(LedState::kTracking), c.tracked);
  EXPECT_EQ(led.updates_in(LedState::kLost) + led.updates_in(LedState::kInitialising),
            c.frames - c.tracked);

  // What the monitor received is what replay estimates, to float precision on the wire. Only
  // when the runtime kept up with every frame (under qemu or the sanitizers it cannot, and
  // with most frames dropped the tracker may end lost).
  std::printf("clip over the link: %d ODOMETRY, %u deadline misses, %u dropped\n", monitor.odometry,
              c.deadline_misses, job.sensor_dropped());
  if (job.sensor_dropped() > 0) return;
  EXPECT_TRUE(gpio->level(job.board().gpio_led_line)) << "tracking: the LED is steady on";
  const std::string clip = testing::source_path("data/tum_fr1_xyz_clip");
  const auto replay = testing::replay_and_evaluate(
      clip, testing::source_path("config/tum_fr1.conf"), {"map.threaded=true"});
  ASSERT_TRUE(replay.ran);
  std::vector<StampedPose> gt;
  int bad = 0;
  ASSERT_TRUE(read_tum_trajectory((clip + "/groundtruth.txt").c_str(), &gt, &bad).is_ok());
  const EvaluationReport received = evaluate_all(gt, monitor.poses, nullptr);
  ASSERT_TRUE(received.ate_ok);
  std::printf("clip over the link: ATE %.3f cm (replay %.3f cm)\n", received.ate.rmse_m * 100,
              replay.report.ate.rmse_m * 100);
  EXPECT_NEAR(received.ate.rmse_m, replay.report.ate.rmse_m, 0.001);
}

// A D435's depth moved into colour on the sensor's own thread (sensor.registration_thread, for a
// board whose tracker core has no room for it) or on the tracker's: the same poses, to the
// threaded mapper's variation.
TEST(Firmware, RegistrationOnTheSensorsThreadTracksAsOnTheTrackers) {
  const std::string dir = testing::make_temp_dir("firmware_registration_thread");
  const std::string config = testing::clip_in_a_depth_camera_of_its_own(dir);
  ASSERT_FALSE(config.empty());
  std::vector<StampedPose> gt;
  int bad = 0;
  ASSERT_TRUE(read_tum_trajectory((dir + "/d435/groundtruth.txt").c_str(), &gt, &bad).is_ok());
  double ate_m[2] = {0, 0};
  for (const bool thread : {false, true}) {
    testing::Monitor monitor;
    RunJob job;
    testing::run_board(&monitor, &job,
                       {"sensor.device=" + dir + "/d435", "sensor.config=" + config,
                        std::string("sensor.registration_thread=") + (thread ? "true" : "false")},
                       "", true);
    const FirmwareCounters& c = job.runtime().counters();
    EXPECT_EQ(c.frames, 50u) << "every frame, held for the tracker";
    EXPECT_EQ(c.tracked, c.frames) << thread;
    const EvaluationReport received = evaluate_all(gt, monitor.poses, nullptr);
    ASSERT_TRUE(received.ate_ok);
    ate_m[thread] = received.ate.rmse_m;
  }
  std::printf("registered on the tracker's thread: ATE %.3f cm; on the sensor's: %.3f cm\n",
              ate_m[0] * 100, ate_m[1] * 100);
  EXPECT_NEAR(ate_m[1], ate_m[0], 0.001);
  EXPECT_LT(ate_m[1], 0.01);
}

TEST(Firmware, SensorErrorsReachTheOperatorAsStatusTextAndAFaultBlink) {
  testing::SyntheticScene scene = testing::SyntheticScene::half_resolution();
  const std::string dir = testing::make_temp_dir("firmware_broken");
  ASSERT_TRUE(testing::write_synthetic_sequence(dir, scene, 12, 10.0));
  ASSERT_TRUE(testing::write_text(dir + "/camera.conf", testing::synthetic_config(scene)));
  // Frame 5's colour image is cut short: the sensor cannot deliver it.
  std::ifstream list(dir + "/rgb.txt");
  std::string line, stamp, path;
  for (int entry = 0; entry <= 5 && std::getline(list, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream(line) >> stamp >> path;
    ++entry;
  }
  ASSERT_TRUE(testing::write_text(dir + "/" + path, "\x89PNG\r\n"));
  testing::Monitor monitor;
  RunJob job;
  testing::run_board(&monitor, &job,
                     {"sensor.device=" + dir, "sensor.config=" + dir + "/camera.conf"});
  const FirmwareCounters& c = job.runtime().counters();
  EXPECT_EQ(c.sensor_errors, 1u);
  bool reported = false;
  for (const std::string& t : monitor.texts) reported |= t.rfind("sensor: ", 0) == 0;
  EXPECT_TRUE(reported) << "no STATUSTEXT for the sensor error";
  EXPECT_GT(job.runtime().led().updates_in(LedState::kFault), 0u) << "the LED must show a fault";
  EXPECT_EQ(monitor.odometry, static_cast<int>(c.frames));
}

// Shifts the recorded times of entries from `first` on by `seconds` in a TUM list file.
void delay_entries(const std::string& list_path, int first, double seconds) {
  std::ifstream in(list_path);
  std::ostringstream out;
  int entry = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') {
      std::istringstream fields(line);
      double stamp = 0;
      std::string path;
      fields >> stamp >> path;
      char shifted[64];
      std::snprintf(shifted, sizeof(shifted), "%.6f", stamp + (entry++ >= first ? seconds : 0));
      line = std::string(shifted) + " " + path;
    }
    out << line << "\n";
  }
  ASSERT_TRUE(testing::write_text(list_path, out.str()));
}

TEST(Firmware, ASilentSensorIsReportedAsAStallAndItsReturnAsARecovery) {
  testing::SyntheticScene scene = testing::SyntheticScene::half_resolution();
  const std::string dir = testing::make_temp_dir("firmware_stall");
  ASSERT_TRUE(testing::write_synthetic_sequence(dir, scene, 12, 10.0));
  ASSERT_TRUE(testing::write_text(dir + "/camera.conf", testing::synthetic_config(scene)));
  // The sensor goes silent for 2.6 s after frame 5.
  delay_entries(dir + "/rgb.txt", 6, 2.5);
  delay_entries(dir + "/depth.txt", 6, 2.5);
  testing::Monitor monitor;
  RunJob job;
  run_synthetic_at_10_hz(&monitor, &job, dir);
  const FirmwareCounters& c = job.runtime().counters();
  EXPECT_EQ(c.frames + job.sensor_dropped(), 12u) << "nothing lost to the stall";
  EXPECT_EQ(c.sensor_recoveries, 1u);
  int stalls = 0, recoveries = 0;
  for (const std::string& t : monitor.texts) {
    std::printf("STATUSTEXT: %s\n", t.c_str());
    // A replay cannot be reopened: the attempt says so, then the frames come back by themselves.
    if (t.rfind("sensor: stall ", 0) == 0) {
      ++stalls;
      EXPECT_NE(t.find("reopen failed"), std::string::npos) << t;
    }
    if (t.rfind("sensor: frames again after ", 0) == 0) {
      ++recoveries;
      const int outage_ms = std::atoi(t.c_str() + std::strlen("sensor: frames again after "));
      // From the last frame delivered before the gap (earlier when a slow tracker, under qemu,
      // had dropped frame 5) to the first after it.
      EXPECT_GE(outage_ms, 1000) << t;
      EXPECT_LE(outage_ms, 3600) << t;
    }
  }
  EXPECT_GE(stalls, 1);
  EXPECT_LE(stalls, 2) << "one attempt per stall period";
  EXPECT_EQ(recoveries, 1);
  EXPECT_EQ(monitor.odometry, static_cast<int>(c.frames));
}

// Polls until done() holds, draining the monitor between tries: waiting on what the firmware's
// threads do, however busy the machine. False (a failure) only when nothing happens for a
// minute.
bool wait_until(testing::Monitor* monitor, const RunJob& job, const std::function<bool()>& done) {
  for (int tries = 0; tries < 60'000; ++tries) {
    monitor->drain(job.board().T_b_c);
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

// Issue 23: what the place store forgets is visible. Every frame a keyframe (overlap 0.99, no
// reuse) into a store of 8 places. The firmware builds keyframes and describes places on threads
// of their own, and one keyframe is in flight at a time: a frame that asks while the last is
// still being built makes none. So that the count is the clip's and not the scheduler's, the
// replay holds every frame for the tracker, the test waits after each frame until the keyframe
// it ordered is built, and the loop module's queue holds the whole clip (its thread describes
// what is queued before it stops). A busy builder once left 7 or 8 places here, under the
// sanitizers.
TEST(Firmware, ThePlaceStoreFillingIsReportedOnceAndCounted) {
  constexpr int kFrames = 30;
  testing::SyntheticScene scene = testing::SyntheticScene::half_resolution();
  scene.diagonal_path = true;
  const std::string dir = testing::make_temp_dir("firmware_places");
  ASSERT_TRUE(testing::write_synthetic_sequence(dir, scene, kFrames, 10.0));
  ASSERT_TRUE(testing::write_text(
      dir + "/camera.conf",
      testing::synthetic_config(scene) +
          "loop.vocabulary = " + testing::source_path("data/vocabulary/tum-k10-l4.voc") +
          "\nloop.places = 8\ntracker.keyframe_overlap = 0.99\nmap.reuse_candidates = 0\n"
          "loop.queue_keyframes = " +
          std::to_string(kFrames + 2) + "\n"));
  testing::Monitor monitor;
  RunJob job;
  bool built_in_time = true;
  monitor.on_step = [&](const RunJob& j) {
    const KeyframeBuildTask& building = j.runtime().slam().keyframe_building();
    built_in_time &= wait_until(&monitor, j, [&] { return building.idle() || building.built(); });
  };
  run_synthetic_at_10_hz(&monitor, &job, dir, /*every_frame=*/true);
  EXPECT_TRUE(built_in_time) << "a keyframe took over a minute to build";
  const SlamSystem& slam = job.runtime().slam();
  const FirmwareCounters& c = job.runtime().counters();
  const uint32_t places = slam.loop().counters().keyframes;
  std::printf("%u places described, %u forgotten by a store of %d (%u frames, %u dropped)\n",
              places, slam.places().evicted(), slam.places().capacity(), c.frames,
              job.sensor_dropped());
  EXPECT_EQ(job.sensor_dropped(), 0u);
  // Every frame a keyframe and a place, but the last: its keyframe is built after the clip, and
  // no later frame takes it up.
  EXPECT_EQ(places, static_cast<uint32_t>(kFrames - 1));
  ASSERT_GT(places, 8u) << "the store must have filled";
  EXPECT_EQ(slam.places().evicted(), places - 8);
  int reported = 0;
  for (const std::string& t : monitor.texts) {
    reported += t == "rgbdtam: place store full (8), forgetting oldest";
  }
  EXPECT_EQ(reported, 1) << "once, when it first fills";
}

// Issue 22: a scripted autopilot on the link. It answers TIMESYNC from a boot clock 10 s into
// the clip, and sends the ground truth's attitude (a body on the board's link.T_b_c, in a level
// frame of its own) at 100 Hz with 0.2 degrees of noise. The ODOMETRY frame must come out level:
// the body's down direction in it is the autopilot's. Issue 35: driven by events, not by the
// scheduler. No frame is dropped, and after each frame the autopilot waits for its ODOMETRY,
// then sends the attitudes up to 0.1 s past it (the next frame's instant) and waits until the
// firmware's link has handed them to the tracker; so every frame after the first has the
// autopilot's turn, on a busy machine as on an idle one.
TEST(Firmware, TheAutopilotsAttitudeLevelsTheOdometryFrameAndGuidesTheTracker) {
  std::vector<StampedPose> truth;
  int bad = 0;
  ASSERT_TRUE(
      read_tum_trajectory(testing::source_path("data/tum_fr1_xyz_clip/groundtruth.txt").c_str(),
                          &truth, &bad)
          .is_ok());
  testing::Monitor monitor;
  RunJob job;
  UdpLink to_firmware;
  mavlink::Encoder autopilot(1, 1);
  const Eigen::Quaterniond q_n_m = so3_exp(Vector3d(0.3, -0.2, 0.7));  // its level frame
  int64_t offset_ns = 0;  // its clock minus the sensor's, fixed at the first request
  bool synced = false;
  int64_t attitudes_until_ns = 0, newest_frame_ns = 0;
  int steps = 0, timesync_answers = 0, stalled = 0, last_sent = 0;
  SE3 T_b_c;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.2 * M_PI / 180.0);
  auto q_n_b = [&](int64_t sensor_ns, Eigen::Quaterniond* q) {
    SE3 T_m_c;
    if (!interpolate_pose(truth, sensor_ns * 1e-9, 0.05, &T_m_c)) return false;
    *q = q_n_m * T_m_c.quaternion() * T_b_c.quaternion().conjugate();
    return true;
  };
  auto send = [&](const auto& m) {
    uint8_t frame[mavlink::kMaxFrameBytes];
    const int n = autopilot.encode(m, frame);
    (void)to_firmware.send(frame, static_cast<size_t>(n));
  };
  monitor.on_frame = [&](const mavlink::Frame& f) {
    if (f.message_id == mavlink::kOdometry.id) {
      mavlink::Odometry o;
      mavlink::unpack(f.payload, f.length, &o);
      newest_frame_ns = static_cast<int64_t>(o.time_usec) * 1000;
    } else if (f.message_id == mavlink::kTimesync.id) {
      mavlink::Timesync t;
      mavlink::unpack(f.payload, f.length, &t);
      if (t.tc1 != 0) return;
      if (!synced) offset_ns = 10'000'000'000 - t.ts1;
      synced = true;
      mavlink::Timesync answer;
      answer.tc1 = t.ts1 + offset_ns;
      answer.ts1 = t.ts1;
      send(answer);
      ++timesync_answers;
    }
  };
  // Sends the attitudes up to until_ns; how many.
  auto send_attitudes = [&](int64_t until_ns) {
    int sent = 0;
    for (; attitudes_until_ns <= until_ns; attitudes_until_ns += 10'000'000) {
      Eigen::Quaterniond q, q_later;
      if (!q_n_b(attitudes_until_ns, &q) || !q_n_b(attitudes_until_ns + 1'000'000, &q_later)) {
        continue;
      }
      const Vector3d rate = so3_log(q.conjugate() * q_later) / 1e-3;
      q = q * so3_exp(Vector3d(noise(rng), noise(rng), noise(rng)));
      mavlink::AttitudeQuaternion a;
      a.time_boot_ms = static_cast<uint32_t>((attitudes_until_ns + offset_ns) / 1'000'000);
      a.q[0] = static_cast<float>(q.w());
      a.q[1] = static_cast<float>(q.x());
      a.q[2] = static_cast<float>(q.y());
      a.q[3] = static_cast<float>(q.z());
      a.rollspeed = static_cast<float>(rate.x());
      a.pitchspeed = static_cast<float>(rate.y());
      a.yawspeed = static_cast<float>(rate.z());
      send(a);
      ++sent;
    }
    return sent;
  };
  monitor.on_step = [&](const RunJob& j) {
    if (to_firmware.local_port() == 0) {
      T_b_c = j.board().T_b_c;
      ASSERT_STREQ(j.board().link_kind, "udp");
      const auto& udp = static_cast<const UdpLink&>(j.link());
      ASSERT_TRUE(to_firmware.open("127.0.0.1", udp.local_port(), 0).is_ok());
    }
    if (steps++ % 10 == 0) send(mavlink::Heartbeat{});
    const LinkTask& link = j.runtime().link();
    // The firmware asks for the autopilot's clock once it has heard it and sent a pose.
    const bool heard = wait_until(&monitor, j, [&] {
      return monitor.odometry == steps && synced && link.autopilot_clock_known();
    });
    if (!heard) {
      ++stalled;
      return;
    }
    // The first attitudes start well before the frame: the firmware reads their times to half
    // a TIMESYNC round trip, which a busy machine makes long.
    if (attitudes_until_ns == 0) attitudes_until_ns = newest_frame_ns - 300'000'000;
    last_sent = send_attitudes(newest_frame_ns + 100'000'000);
    if (!wait_until(&monitor, j, [&] { return link.attitudes_waiting() == last_sent; })) {
      ++stalled;
    }
  };
  testing::run_board(&monitor, &job, {}, "", /*every_frame=*/true);
  const FirmwareRuntime& runtime = job.runtime();
  const AttitudeAidCounters& a = runtime.attitude().counters();
  const TrackingCounters& t = runtime.slam().tracking().counters();
  const PoseLinkCounters& lc = runtime.link().counters();
  const FirmwareCounters& c = runtime.counters();
  std::printf(
      "autopilot: %d TIMESYNC answered; %llu attitudes received, %u kept; levelled %u times, "
      "reset_counter moved %u; prior on %u of %u frames: %u stood, %u refused; %u retried\n",
      timesync_answers, static_cast<unsigned long long>(lc.attitudes), a.samples, a.levellings,
      lc.frame_changes, a.priors, c.frames, t.prior_used, t.prior_rejected, t.retried);
  EXPECT_EQ(stalled, 0) << "the firmware stopped answering";
  EXPECT_EQ(job.sensor_dropped(), 0u);
  EXPECT_EQ(c.frames, 50u);
  ASSERT_TRUE(runtime.attitude().levelled());
  EXPECT_EQ(a.levellings, 1u);
  // Every attitude received is kept, but those sent after the last frame (never taken).
  EXPECT_EQ(a.samples + last_sent, lc.attitudes);
  EXPECT_EQ(lc.attitudes_unsynced, 0u);
  // Every frame but the first has the autopilot's turn since the frame before it.
  EXPECT_EQ(a.priors, c.frames - 1);
  EXPECT_EQ(t.prior_used + t.prior_rejected, a.priors);
  EXPECT_LE(t.prior_rejected * 10, a.priors) << "the truth stands";
  // After the change of frame (one reset_counter step), the body's down is the autopilot's.
  int checked = 0, valid_after = 0;
  double worst_deg = 0;
  const uint8_t levelled_reset = static_cast<uint8_t>(lc.frame_changes);
  for (const mavlink::Odometry& o : monitor.odometry_messages) {
    if (o.quality < 0 || o.reset_counter != levelled_reset) continue;
    ++valid_after;
    Eigen::Quaterniond q_truth;
    if (!q_n_b(static_cast<int64_t>(o.time_usec) * 1000, &q_truth)) continue;
    const Eigen::Quaterniond q_l_b(o.q[0], o.q[1], o.q[2], o.q[3]);
    const Vector3d down_sent = q_l_b.conjugate() * Vector3d::UnitZ();
    const Vector3d down_truth = q_truth.conjugate() * Vector3d::UnitZ();
    worst_deg =
        std::max(worst_deg, std::acos(std::min(1.0, down_sent.dot(down_truth))) * 180 / M_PI);
    ++checked;
  }
  std::printf(
      "gravity in ODOMETRY's frame: %d poses checked, worst %.2f deg from the autopilot's\n",
      checked, worst_deg);
  EXPECT_EQ(checked, valid_after) << "the truth covers the clip";
  // Levelled after the ten poses it needs, from the second frame on.
  EXPECT_GE(checked, 30);
  EXPECT_LT(worst_deg, 2.0);
}

TEST(Firmware, ABoardsMapFileIsSavedAtTheEndAndTheNextRunIsFoundInIt) {
  const std::string map = testing::make_temp_dir("firmware_map") + "/board.map";
  testing::Monitor first_monitor;
  auto first = std::make_unique<RunJob>();
  // The clip lasts 1.7 s: a save while running, by the loop thread (more where the run is slow,
  // as under emulation), then the one at the end.
  testing::run_board(&first_monitor, first.get(), {"map.file=" + map, "map.save_period_s=1"});
  ASSERT_TRUE(first->map_saved().is_ok()) << first->map_saved().message();
  EXPECT_GE(first->map_checkpoint().saves(), 1u);
  EXPECT_EQ(first->map_checkpoint().failures(), 0u)
      << first->map_checkpoint().last_failure().message();
  EXPECT_EQ(first->loaded_map().places, 0u) << "none yet: made at the end";
  const int places = first->runtime().slam().places().size();
  EXPECT_GT(places, 0);

  testing::Monitor monitor;
  auto second = std::make_unique<RunJob>();
  testing::run_board(&monitor, second.get(), {"map.file=" + map});
  EXPECT_EQ(second->loaded_map().places, static_cast<uint32_t>(places));
  int found = 0;
  for (const std::string& t : monitor.texts) {
    found += t == "rgbdtam: found in the saved map, poses in its frame";
  }
  EXPECT_EQ(found, 1);
  ASSERT_FALSE(monitor.poses.empty());
  // The clip starts where the first run started: the saved world's origin.
  EXPECT_LT(monitor.poses.front().T_w_c.translation().norm(), 0.02);
  EXPECT_TRUE(second->map_saved().is_ok());
}

TEST(Firmware, EveryOdometrySentHasItsLatencyFromTheFramesArrival) {
  testing::Monitor monitor;
  RunJob job;
  testing::run_board(&monitor, &job, {});
  const LatencyStats& latency = job.runtime().link().arrival_to_odometry();
  EXPECT_EQ(static_cast<uint64_t>(latency.count()), job.runtime().link().counters().odometry_sent);
  EXPECT_GT(latency.count(), 0);
  // A frame is tracked between its arrival and its ODOMETRY: never instantaneous.
  EXPECT_GT(latency.percentile_ms(0.5), 0.0);
  EXPECT_GE(latency.percentile_ms(0.95), latency.percentile_ms(0.5));
  // Percentiles are read from 10 us bins, the maximum exactly.
  EXPECT_GE(latency.max_ms() + LatencyStats::kBinNs * 1e-6, latency.percentile_ms(0.95));
  std::printf(
      "arrival to ODOMETRY ms: median %.2f, p95 %.2f, max %.2f; tracker task median "
      "%.2f\n",
      latency.percentile_ms(0.5), latency.percentile_ms(0.95), latency.max_ms(),
      job.runtime().tracker_time().percentile_ms(0.5));
}

TEST(Firmware, ObstacleDistanceGoesOutAtTheBoardsRateInTheBodyFrame) {
  testing::Monitor monitor;
  RunJob job;
  testing::run_board(&monitor, &job, {});
  // 10 Hz on a 30 Hz clip: every third frame, never faster (a slow build, under emulation or
  // the sanitizers, may drop frames and send fewer).
  const uint32_t frames = job.runtime().counters().frames;
  const double by_time = (frames + job.sensor_dropped()) / 3.0;
  EXPECT_LE(static_cast<double>(monitor.obstacles.size()), by_time + 1.0);
  EXPECT_GE(monitor.obstacles.size(), 1u);
  if (job.sensor_dropped() == 0) {
    EXPECT_NEAR(static_cast<double>(monitor.obstacles.size()), by_time, 1.0);
  }
  EXPECT_EQ(job.runtime().counters().obstacle_reports, monitor.obstacles.size());
  int known = 0;
  for (const mavlink::ObstacleDistance& o : monitor.obstacles) {
    EXPECT_EQ(o.frame, mavlink::kMavFrameBodyFrd);
    EXPECT_EQ(o.min_distance, 30);
    EXPECT_EQ(o.max_distance, 500);
    EXPECT_NEAR(o.increment_f * 72, 63.48, 0.05);  // the clip camera's horizontal view
    for (const uint16_t d : o.distances) known += d != UINT16_MAX;
  }
  EXPECT_GT(known, static_cast<int>(monitor.obstacles.size()) * 36);

  testing::Monitor off_monitor;
  RunJob off;
  testing::run_board(&off_monitor, &off, {"obstacle.rate_hz=0"});
  EXPECT_TRUE(off_monitor.obstacles.empty());
}

TEST(Firmware, StoppingDuringARecordedGapOfAYearTakesNoLongerThanAFrame) {
  // One stamp a year late used to make the sensor thread sleep a year, and Ctrl-C join it.
  testing::SyntheticScene scene = testing::SyntheticScene::half_resolution();
  const std::string dir = testing::make_temp_dir("firmware_gap");
  ASSERT_TRUE(testing::write_synthetic_sequence(dir, scene, 12, 10.0));
  ASSERT_TRUE(testing::write_text(dir + "/camera.conf", testing::synthetic_config(scene)));
  delay_entries(dir + "/rgb.txt", 6, 365.0 * 86400);
  delay_entries(dir + "/depth.txt", 6, 365.0 * 86400);
  testing::Monitor monitor;
  RunJob job;
  using Clock = std::chrono::steady_clock;
  std::atomic<int64_t> stop_requested_ns{0};
  std::thread ctrl_c([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // well into the gap
    stop_requested_ns = Clock::now().time_since_epoch().count();
    job.request_stop();
  });
  run_synthetic_at_10_hz(&monitor, &job, dir);
  const int64_t finished_ns = Clock::now().time_since_epoch().count();
  ctrl_c.join();
  const double stop_s = (finished_ns - stop_requested_ns.load()) * 1e-9;
  std::printf("stopped %.3f s after the request, in a gap of a year\n", stop_s);
  EXPECT_LT(stop_s, 2.0) << "a frame period and 100 ms, with room for a loaded machine";
  EXPECT_LE(job.runtime().counters().frames, 6u);
}

// A transport that keeps what it is given (the link thread writes, the test reads after stop).
class CaptureLink : public ByteLink {
 public:
  bool send(const uint8_t* bytes, size_t n) override {
    bytes_.insert(bytes_.end(), bytes, bytes + n);
    ++counters_.tx_frames;
    return true;
  }
  size_t receive(uint8_t*, size_t) override { return 0; }
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

// A firmware runtime on the synthetic camera without mapping, its link captured, its clock at 0.
void init_bare_runtime(const testing::SyntheticScene& scene, CaptureLink* link, FakeGpio* gpio,
                       FirmwareRuntime* runtime) {
  Params params;
  ASSERT_TRUE(parse_params(testing::synthetic_config(scene).c_str(), "synthetic", &params).is_ok());
  params.sensor.disparity_sigma_px = 0.1;
  params.map_enabled = false;
  Board board;
  ASSERT_TRUE(parse_board("board.name = test\nbuild.preset = host-release\nboard.cpu_count = 1\n"
                          "sensor.kind = replay\nsensor.device = x\nsensor.config = y\n"
                          "link.kind = udp\nlink.udp_remote = 127.0.0.1:9\n",
                          "test", ".", &board)
                  .is_ok());
  ASSERT_TRUE(runtime->init(params, board, link, gpio, [] { return int64_t{0}; }).is_ok());
}

TEST(Firmware, TrackingLostAndRegainedAreReportedOnceEach) {
  testing::SyntheticScene scene = testing::SyntheticScene::half_resolution();
  CaptureLink link;
  FakeGpio gpio;
  FirmwareRuntime runtime;
  // Tracking health is what this test is about.
  ASSERT_NO_FATAL_FAILURE(init_bare_runtime(scene, &link, &gpio, &runtime));
  ASSERT_TRUE(runtime.start().is_ok());
  const auto& frames = scene.render_path(20, 10.0);
  const std::vector<uint8_t> black(frames[0].gray.size(), 0);
  for (int i = 0; i < 20; ++i) {
    SensorFrame f = frames[static_cast<size_t>(i)].as_sensor_frame(scene.camera, i, 10.0);
    if (i >= 8 && i < 12) {  // the lens covered: nothing to track, no depth
      f.gray = black.data();
      f.depth = nullptr;
    }
    (void)runtime.on_frame(f, 0);
  }
  runtime.stop();
  std::vector<std::string> texts;
  int odometry = 0, lost = 0;
  mavlink::Decoder decoder;
  mavlink::StatusTextJoiner joiner;
  decoder.feed_all(link.bytes().data(), link.bytes().size(), [&](const mavlink::Frame& f) {
    if (f.message_id == mavlink::kStatusText.id) {
      mavlink::StatusText t;
      mavlink::unpack(f.payload, f.length, &t);
      if (const char* whole = joiner.add(t)) texts.emplace_back(whole);  // chunks joined
    } else if (f.message_id == mavlink::kOdometry.id) {
      mavlink::Odometry o;
      mavlink::unpack(f.payload, f.length, &o);
      ++odometry;
      lost += o.quality < 0 ? 1 : 0;
    }
  });
  EXPECT_EQ(odometry, 20);
  EXPECT_EQ(lost, static_cast<int>(runtime.counters().lost));
  EXPECT_GE(lost, 1);
  // Lost once, saying which health checks failed, and regained once.
  ASSERT_EQ(texts.size(), 2u);
  EXPECT_EQ(texts[0].rfind("rgbdtam: lost: ", 0), 0u) << texts[0];
  EXPECT_EQ(texts[0].find("healthy"), std::string::npos) << texts[0];
  EXPECT_EQ(texts[1], "rgbdtam: tracking regained");
  std::printf("STATUSTEXT: '%s'\n", texts[0].c_str());
}

TEST(Firmware, ASensorFailingEveryReadIsReportedOncePerOutageNotPerRead) {
  CaptureLink link;
  FakeGpio gpio;
  FirmwareRuntime runtime;
  ASSERT_NO_FATAL_FAILURE(
      init_bare_runtime(testing::SyntheticScene::half_resolution(), &link, &gpio, &runtime));
  const Status unplugged = Status::error(StatusCode::kIoError, "device unplugged");
  constexpr int64_t kFrameNs = 33'000'000;
  for (int i = 0; i < 60; ++i) runtime.on_sensor_error(unplugged, i * kFrameNs);  // 2 s
  EXPECT_EQ(runtime.counters().status_texts, 1u) << "one message for the outage";
  for (int i = 60; i < 240; ++i) runtime.on_sensor_error(unplugged, i * kFrameNs);  // 8 s in
  EXPECT_EQ(runtime.counters().status_texts, 2u) << "and one more 5 s later";
  runtime.on_sensor_recovered(240 * kFrameNs);
  runtime.on_sensor_error(unplugged, 241 * kFrameNs);  // a new outage is news at once
  const FirmwareCounters& c = runtime.counters();
  EXPECT_EQ(c.status_texts, 4u);
  EXPECT_EQ(c.sensor_errors, 241u);
  EXPECT_EQ(c.sensor_texts_withheld, 241u - 3u);
}

TEST(Firmware, HostEmulationOverASerialPortAt115200CarriesEveryPose) {
  // The link on a pseudo-terminal as the robot's UART; this test reads the other end.
  int master = -1, slave = -1;
  char name[128];
  ASSERT_EQ(::openpty(&master, &slave, name, nullptr, nullptr), 0);
  std::atomic<bool> done{false};
  testing::Monitor monitor;
  std::vector<uint8_t> bytes;
  std::thread reader([&] {
    uint8_t buf[4096];
    ::fcntl(master, F_SETFL, ::fcntl(master, F_GETFL) | O_NONBLOCK);
    for (int idle = 0; !done.load() || idle < 20;) {
      const ssize_t n = ::read(master, buf, sizeof(buf));
      if (n > 0) {
        bytes.insert(bytes.end(), buf, buf + n);
        idle = 0;
      } else {
        ++idle;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    }
  });
  RunJob job;
  static const std::string board = testing::source_path("board/host-emulation");
  const std::string device = std::string("link.serial_device=") + name;
  RunOptions options;
  options.board_dir = board.c_str();
  options.board_overrides[options.board_override_count++] = "link.kind=serial";
  options.board_overrides[options.board_override_count++] = "link.baud=115200";
  options.board_overrides[options.board_override_count++] = device.c_str();
  options.progress = false;
  ASSERT_TRUE(job.init(options).is_ok());
  ASSERT_TRUE(job.start().is_ok());
  while (job.step()) {
  }
  job.finish();
  done = true;
  reader.join();
  ::close(master);
  ::close(slave);
  int odometry = 0;
  monitor.decoder.feed_all(bytes.data(), bytes.size(), [&](const mavlink::Frame& f) {
    odometry += f.message_id == mavlink::kOdometry.id ? 1 : 0;
  });
  const FirmwareCounters& c = job.runtime().counters();
  EXPECT_EQ(odometry, static_cast<int>(c.frames));
  EXPECT_EQ(job.runtime().link().counters().odometry_rate_limited, 0u);
  EXPECT_EQ(monitor.decoder.counters().crc_errors, 0u);
  EXPECT_EQ(job.link().counters().drops, 0u);
}

}  // namespace
}  // namespace rgbdtam

// Loop closure and relocalisation, measured (tools/loop_bench.sh):
//   rgbdtam-loop-bench replay <sequence> --config <file> [--set key=value]...
//     replays the sequence and prints accuracy (live and final map), coverage, false-valid poses,
//     and place recognition's precision and recall against the ground truth;
//   rgbdtam-loop-bench costs <sequence> --config <file>
//     vocabulary size and load time, features per keyframe, query time, pose-graph time for
//     32, 256 and 1024 keyframes, and the light store's memory at capacity.
// Host tool: allocates freely.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "config_files.hpp"
#include "evaluate_command.hpp"
#include "frontend_frames.hpp"
#include "replay_job.hpp"
#include "rgbdtam/core/pose_graph.hpp"
#include "rgbdtam/hal/clock.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/runtime/place_recognition.hpp"

namespace rgbdtam {
namespace {

// Ground truth at a time, when a sample lies within 20 ms.
bool truth_at(const std::vector<StampedPose>& gt, double t, SE3* T) {
  const auto it = std::lower_bound(gt.begin(), gt.end(), t,
                                   [](const StampedPose& p, double s) { return p.stamp_s < s; });
  const StampedPose* best = nullptr;
  if (it != gt.end()) best = &*it;
  if (it != gt.begin() && (best == nullptr || t - (it - 1)->stamp_s < best->stamp_s - t)) {
    best = &*(it - 1);
  }
  if (best == nullptr || std::fabs(best->stamp_s - t) > 0.02) return false;
  *T = best->T_w_c;
  return true;
}

// A relative pose within the false-valid tolerance of the truth (10 cm, 5 degrees).
bool agrees(const SE3& estimate, const SE3& truth) {
  const SE3 e = truth.inverse() * estimate;
  return e.translation().norm() <= 0.10 && so3_log(e.quaternion()).norm() <= 5.0 * M_PI / 180.0;
}

struct Recorder : LoopObserver {
  std::vector<PlaceMatchEvent> events;
  void on_verified(const PlaceMatchEvent& e) override { events.push_back(e); }
};

int replay(const std::string& sequence, const Params& params) {
  Recorder recorder;
  ReplayOptions opt;
  opt.sequence = sequence.c_str();
  opt.params = params;
  opt.progress = false;
  opt.loop_observer = &recorder;
  ReplayJob job;
  Status s = job.init(opt);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam-loop-bench: %s\n", s.message());
    return 1;
  }
  // Keyframes and the stretch (between restarts) each belongs to.
  struct Keyframe {
    int64_t t_ns;
    int segment;
  };
  std::vector<Keyframe> keyframes;
  int segment = 0;
  while (job.step()) {
    const PoseEstimate& p = job.last_pose();
    const bool restart =
        (p.flags & kReset) != 0 && (p.flags & (kRelocalised | kLoopCorrected)) == 0;
    segment += restart ? 1 : 0;
    if ((p.flags & kNewKeyframe) != 0) keyframes.push_back({p.timestamp_ns, segment});
  }
  s = job.finish();
  std::vector<StampedPose> gt;
  int bad = 0;
  s = read_tum_trajectory((sequence + "/groundtruth.txt").c_str(), &gt, &bad);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam-loop-bench: %s\n", s.message());
    return 1;
  }
  std::vector<double> stamps;
  for (int i = 0; i < job.source().rgb_list().size; ++i) {
    stamps.push_back(job.source().rgb_list().entries[i].timestamp_ns * 1e-9);
  }
  const EvaluationReport live = evaluate_all(gt, job.estimates(), &stamps);
  const EvaluationReport final_map = evaluate_all(gt, job.final_estimates(), &stamps);
  // Precision: every verified match (and every loop) against the ground truth's relative pose.
  int verified = 0, verified_right = 0, loops = 0, loops_right = 0, unknown = 0;
  std::map<int64_t, bool> found;  // query keyframe -> a right match was verified
  for (const PlaceMatchEvent& e : recorder.events) {
    SE3 T_w_q, T_w_p;
    if (!truth_at(gt, e.query_ns * 1e-9, &T_w_q) || !truth_at(gt, e.place_ns * 1e-9, &T_w_p)) {
      ++unknown;
      continue;
    }
    const bool right = agrees(e.T_place_query, T_w_p.inverse() * T_w_q);
    ++verified;
    verified_right += right;
    loops += e.loop;
    loops_right += e.loop && right;
    if (right) found[e.query_ns] = true;
    if (!right) {
      std::printf("  wrong match: keyframe at %.3f s to the one at %.3f s (%d inliers%s)\n",
                  e.query_ns * 1e-9, e.place_ns * 1e-9, e.inliers, e.loop ? ", loop" : "");
    }
  }
  // Recall: keyframes that revisit a place the loop module may match (an older stretch, or the
  // same one at least loop.min_age earlier) within 30 cm and 20 degrees, per the ground truth.
  int revisits = 0, revisits_found = 0;
  for (size_t i = 0; i < keyframes.size(); ++i) {
    SE3 T_i;
    if (!truth_at(gt, keyframes[i].t_ns * 1e-9, &T_i)) continue;
    bool revisit = false;
    for (size_t j = 0; j < i && !revisit; ++j) {
      const bool allowed = keyframes[j].segment != keyframes[i].segment ||
                           (keyframes[i].t_ns - keyframes[j].t_ns) * 1e-9 >= params.loop.min_age_s;
      SE3 T_j;
      if (!allowed || !truth_at(gt, keyframes[j].t_ns * 1e-9, &T_j)) continue;
      const SE3 d = T_j.inverse() * T_i;
      revisit = d.translation().norm() < 0.3 && so3_log(d.quaternion()).norm() < 20 * M_PI / 180;
    }
    revisits += revisit;
    const auto it = found.find(keyframes[i].t_ns);
    revisits_found += revisit && it != found.end();
  }
  const TrackingCounters& c = job.counters();
  const LoopCounters& l = job.loop_counters();
  std::printf(
      "live: ATE %.2f cm, coverage %.1f %%, false-valid %d of %d; final map: ATE %.2f cm, "
      "coverage %.1f %%\n",
      100 * live.ate.rmse_m, 100 * live.coverage.fraction(), live.false_valid.count,
      live.false_valid.checked, 100 * final_map.ate.rmse_m, 100 * final_map.coverage.fraction());
  std::printf(
      "events: %u lost, %u restarts, %u relocalised, %u loop corrections, %u withheld; %zu "
      "keyframes\n",
      c.lost, c.resets, c.relocalised, c.loop_corrections, c.withheld, keyframes.size());
  std::printf(
      "place recognition: %d verified matches, %d right (precision %.1f %%); %d loops, %d right "
      "(precision %.1f %%); recall %d of %d revisiting keyframes (%.1f %%); %d without ground "
      "truth; %u candidates checked\n",
      verified, verified_right, verified > 0 ? 100.0 * verified_right / verified : 100.0, loops,
      loops_right, loops > 0 ? 100.0 * loops_right / loops : 100.0, revisits_found, revisits,
      revisits > 0 ? 100.0 * revisits_found / revisits : 0.0, unknown, l.candidates);
  return verified_right == verified ? 0 : 3;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

double pose_graph_ms(int n) {
  // A chain that drifts 0.5 degrees a step, closed by a loop every 16 keyframes.
  PoseGraph g;
  g.allocate(n, 2 * n);
  std::vector<SE3> truth;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    truth.push_back(SE3(so3_exp(Vector3d(0, a, 0)), Vector3d(std::cos(a), 0, std::sin(a))));
  }
  const SE3 bias(so3_exp(Vector3d(0, 0.5 * M_PI / 180, 0)), Vector3d(0.002, 0, 0));
  SE3 drifted = truth[0];
  g.add_node(drifted);
  for (int i = 1; i < n; ++i) {
    const SE3 step = truth[i - 1].inverse() * truth[i] * bias;
    drifted = drifted * step;
    g.add_node(drifted);
    g.add_edge(i - 1, i, step, 1e4 * Matrix6d::Identity());
  }
  for (int i = 16; i < n; i += 16) {
    g.add_edge(0, i, truth[0].inverse() * truth[i], 1e5 * Matrix6d::Identity());
  }
  const int64_t t0 = monotonic_ns();
  g.optimize(10);
  return (monotonic_ns() - t0) * 1e-6;
}

int costs(const std::string& sequence, const Params& params) {
  // The vocabulary: size and load time.
  Vocabulary voc;
  std::vector<double> load_ms;
  for (int i = 0; i < 5; ++i) {
    Status error;
    const int64_t t0 = monotonic_ns();
    if (!load_vocabulary(params, &voc, &error)) {
      std::fprintf(stderr, "rgbdtam-loop-bench: %s\n", error.message());
      return 1;
    }
    load_ms.push_back((monotonic_ns() - t0) * 1e-6);
  }
  std::unique_ptr<uint8_t[]> bytes;
  size_t size = 0;
  (void)read_binary_file(params.loop.vocabulary, size_t{256} << 20, &bytes, &size);
  std::printf("vocabulary: %s, %zu bytes, %d words; load median %.1f ms\n", params.loop.vocabulary,
              size, voc.words(), median(load_ms));
  // Features and bag of words per keyframe: every 20th frame of the sequence.
  FrontendFrames frames;
  const Status s = frames.open(sequence.c_str(), params);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam-loop-bench: %s\n", s.message());
    return 1;
  }
  PlaceRecognizer recognizer;
  recognizer.allocate(params);
  PlaceStore store;
  store.allocate(params.loop.places, params.loop.features, voc.words());
  std::vector<double> describe_ms;
  std::vector<std::vector<Feature>> features;
  std::vector<std::vector<BowEntry>> bows;
  for (int i = 0; i < frames.count(); i += 20) {
    if (!frames.load(i)) continue;
    const FramePyramid& frame = frames.frame();
    const int64_t t0 = monotonic_ns();
    recognizer.describe(frame.gray(0), frame.inverse_depth(0), frame.intrinsics(0), voc);
    describe_ms.push_back((monotonic_ns() - t0) * 1e-6);
    features.emplace_back(recognizer.features().begin(), recognizer.features().end());
    bows.emplace_back(recognizer.bow().begin(), recognizer.bow().end());
  }
  if (features.empty()) {
    std::fprintf(stderr, "rgbdtam-loop-bench: no frame with depth in %s\n", sequence.c_str());
    return 1;
  }
  double mean_features = 0;
  for (const auto& f : features) mean_features += f.size();
  std::printf(
      "features + bag of words per keyframe: median %.2f ms, %.0f features (%zu "
      "keyframes)\n",
      median(describe_ms), mean_features / features.size(), features.size());
  // The store filled to capacity with the sequence's keyframes over and over; query and verify.
  for (int i = 0; i < store.capacity(); ++i) {
    const size_t k = static_cast<size_t>(i) % features.size();
    PlaceRecord* r = store.begin_insert();
    r->keyframe_id = static_cast<uint32_t>(i);
    for (const Feature& f : features[k]) (void)r->features.push_back(f);
    for (const BowEntry& e : bows[k]) (void)r->bow.push_back(e);
    store.commit();
  }
  std::vector<double> query_ms, verify_ms;
  const VerificationLimits limits = VerificationLimits::of(params);
  BowVector bow;
  bow.reserve_once(params.loop.features);
  for (size_t k = 0; k < bows.size(); ++k) {
    bow.clear();
    for (const BowEntry& e : bows[k]) (void)bow.push_back(e);
    PlaceMatch m[8];
    const int64_t t0 = monotonic_ns();
    const int n = store.database().query(bow, nullptr, nullptr, m, 8);
    query_ms.push_back((monotonic_ns() - t0) * 1e-6);
    if (n == 0) continue;
    const int64_t t1 = monotonic_ns();
    (void)recognizer.verify(store.at_slot(m[0].slot), limits);
    verify_ms.push_back((monotonic_ns() - t1) * 1e-6);
  }
  std::printf(
      "query of %d places: median %.2f ms; one verification (match + RANSAC): median "
      "%.2f ms\n",
      store.capacity(), median(query_ms), median(verify_ms));
  std::printf(
      "pose graph, 10 Gauss-Newton steps: 32 keyframes %.2f ms, 256 %.2f ms, 1024 %.1f ms\n",
      pose_graph_ms(32), pose_graph_ms(256), pose_graph_ms(1024));
  std::printf(
      "light store at capacity (%d places of %d features, with its index): %.1f MB\n",
      params.loop.places, params.loop.features,
      PlaceStore::bytes_needed(params.loop.places, params.loop.features, voc.words()) / 1048576.0);
  return 0;
}

}  // namespace
}  // namespace rgbdtam

int main(int argc, char** argv) {
  using namespace rgbdtam;
  if (argc < 3 || (std::strcmp(argv[1], "replay") != 0 && std::strcmp(argv[1], "costs") != 0)) {
    std::fprintf(stderr,
                 "usage: rgbdtam-loop-bench replay|costs <sequence> --config <file> "
                 "[--set key=value]...\n");
    return 2;
  }
  Params params;
  bool have_config = false;
  for (int i = 3; i < argc; ++i) {
    Status s;
    if (std::strcmp(argv[i], "--config") == 0 && i + 1 < argc) {
      s = read_params_file(argv[++i], &params);
      have_config = true;
    } else if (std::strcmp(argv[i], "--set") == 0 && i + 1 < argc) {
      s = set_param(argv[++i], "--set", &params);
    } else {
      std::fprintf(stderr, "rgbdtam-loop-bench: unknown argument '%s'\n", argv[i]);
      return 2;
    }
    if (!s.is_ok()) {
      std::fprintf(stderr, "rgbdtam-loop-bench: %s\n", s.message());
      return 1;
    }
  }
  if (!have_config) {
    std::fprintf(stderr, "rgbdtam-loop-bench: --config is required\n");
    return 2;
  }
  return std::strcmp(argv[1], "replay") == 0 ? replay(argv[2], params) : costs(argv[2], params);
}

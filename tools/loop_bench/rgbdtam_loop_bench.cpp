// Loop closure and relocalisation, measured (tools/loop_bench.sh):
//   rgbdtam-loop-bench replay <sequence> --config <file> [--set key=value]...
//     replays the sequence and prints accuracy (live and final map), coverage, false-valid poses,
//     and place recognition's precision and recall against the ground truth;
//   rgbdtam-loop-bench costs <sequence> --config <file>
//     vocabulary size and load time, features per keyframe, query time, pose-graph time for
//     32, 256 and 1024 keyframes, and the light store's memory at capacity.
// Host tool: allocates freely.
#include <malloc.h>

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
#include "rgbdtam/hal/machine.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/runtime/place_recognition.hpp"
#include "view_study.hpp"

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

// The revisit measure (issue 19): a keyframe revisits when the ground truth puts an older
// keyframe, more than kRevisitGapS earlier, within 15 cm and 20 degrees of it; it is found when
// an edge of the keyframe graph joins it to a keyframe more than kRevisitGapS older. An edge is
// right when its relative pose is within 5 cm and 3 degrees of the ground truth's.
constexpr double kRevisitGapS = 5.0;
constexpr double kRevisitDistanceM = 0.15, kRevisitAngleRad = 20 * M_PI / 180;
constexpr double kEdgeToleranceM = 0.05, kEdgeToleranceRad = 3 * M_PI / 180;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct Recorder : LoopObserver {
  std::vector<GraphEdgeEvent> edges;
  struct Moved {
    uint32_t correction, keyframe_id;
    SE3 before, after;
  };
  std::vector<Moved> moved;
  // What this bench keeps of the run to check it afterwards (not the system's memory).
  size_t bytes() const {
    return edges.capacity() * sizeof(GraphEdgeEvent) + moved.capacity() * sizeof(Moved);
  }
  void on_edge(const GraphEdgeEvent& e) override {
    if (e.kind != EdgeKind::kRestart) edges.push_back(e);  // no measurement: no error to check
  }
  void on_place_moved(uint32_t correction, uint32_t keyframe_id, const SE3& before,
                      const SE3& after) override {
    moved.push_back({correction, keyframe_id, before, after});
  }
};

// Each correction against the ground truth: the ATE of the places it moved (at their
// keyframes' times), before and after it.
void check_corrections(const Recorder& recorder, const std::map<uint32_t, double>& keyframe_s,
                       const std::vector<StampedPose>& gt) {
  std::vector<double> before_cm, after_cm;
  int worse = 0;
  for (size_t i = 0; i < recorder.moved.size();) {
    std::vector<StampedPose> before, after;
    const uint32_t correction = recorder.moved[i].correction;
    for (; i < recorder.moved.size() && recorder.moved[i].correction == correction; ++i) {
      const auto t = keyframe_s.find(recorder.moved[i].keyframe_id);
      if (t == keyframe_s.end()) continue;
      before.push_back({t->second, recorder.moved[i].before});
      after.push_back({t->second, recorder.moved[i].after});
    }
    auto by_time = [](const StampedPose& a, const StampedPose& b) { return a.stamp_s < b.stamp_s; };
    std::sort(before.begin(), before.end(), by_time);
    std::sort(after.begin(), after.end(), by_time);
    AteResult b, a;
    if (!evaluate_ate(gt, before, &b) || !evaluate_ate(gt, after, &a)) continue;
    before_cm.push_back(100 * b.rmse_m);
    after_cm.push_back(100 * a.rmse_m);
    // Worse by more than a millimetre: the correction moved the places away from the truth.
    worse += a.rmse_m > b.rmse_m + 0.001;
  }
  if (before_cm.empty()) return;
  std::printf(
      "corrections against the ground truth: %zu checked; ATE of the places they moved, median "
      "%.2f cm before, %.2f cm after (worst after %.2f cm); %d made it worse by more than 1 mm\n",
      before_cm.size(), median(before_cm), median(after_cm),
      *std::max_element(after_cm.begin(), after_cm.end()), worse);
}

int replay(const std::string& sequence, const Params& params, const std::string& row) {
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
  std::map<uint32_t, double> keyframe_s;  // keyframe id -> its frame's time
  // Outages (a gap in the frames of more than kGapS): how many frames after each the first
  // valid pose came, and how it came.
  constexpr double kGapS = 0.2;
  struct Outage {
    double gap_s = 0;
    int frames_to_valid = -1;
    uint32_t flags = 0;
  };
  std::vector<Outage> outages;
  double previous_s = -1;
  // Resident memory after init, when both stores are first full (every slot touched), and at
  // the end; the bench's own records of the run grow in between and are counted apart, and
  // what their growth freed is handed back first (glibc keeps freed heap resident).
  const double mb = 1 << 20;
  auto resident_mb = [&] {
    (void)malloc_trim(0);
    return resident_bytes() / mb;
  };
  const double init_mb = resident_mb();
  double full_mb = 0, full_records_mb = 0;
  int frames = 0, full_frame = 0;
  const PlaceStore& places = job.system().places();
  const KeyframePool& pool = job.system().tracking().keyframes();
  constexpr size_t kMapNodeBytes = 64;  // a std::map node: key, value, three links, rounded up
  auto records_mb = [&] { return (recorder.bytes() + keyframe_s.size() * kMapNodeBytes) / mb; };
  while (job.step()) {
    ++frames;
    if (full_frame == 0 && places.evicted() > 0 && pool.recycled() > 0) {
      full_frame = frames;
      full_mb = resident_mb();
      full_records_mb = records_mb();
    }
    const PoseEstimate& p = job.last_pose();
    const double t = p.timestamp_ns * 1e-9;
    if ((p.flags & kNewKeyframe) != 0) keyframe_s[p.keyframe_id] = t;
    if (previous_s >= 0 && t - previous_s > kGapS) outages.push_back({t - previous_s, -1, 0});
    previous_s = t;
    if (!outages.empty() && outages.back().frames_to_valid < 0) {
      Outage& o = outages.back();
      ++o.flags;  // counts frames until valid, then holds the flags
      if ((p.flags & kPoseValid) != 0) {
        o.frames_to_valid = static_cast<int>(o.flags) - 1;
        o.flags = p.flags;
      }
    }
  }
  const double end_mb = resident_mb();
  const double end_records_mb = records_mb();
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
  // Precision, per kind of edge; the keyframes each revisit edge joins.
  int edges[kEdgeKinds] = {}, wrong[kEdgeKinds] = {}, unknown = 0;
  std::vector<double> error_cm[kEdgeKinds];
  std::map<uint32_t, bool> joined_to_older;  // keyframe id -> a revisit edge to an older one
  for (const GraphEdgeEvent& e : recorder.edges) {
    const auto from = keyframe_s.find(e.from_id), to = keyframe_s.find(e.to_id);
    SE3 T_w_from, T_w_to;
    if (from == keyframe_s.end() || to == keyframe_s.end() ||
        !truth_at(gt, from->second, &T_w_from) || !truth_at(gt, to->second, &T_w_to)) {
      ++unknown;
      continue;
    }
    const int k = static_cast<int>(e.kind);
    ++edges[k];
    const SE3 error = (T_w_from.inverse() * T_w_to).inverse() * e.T_from_to;
    error_cm[k].push_back(100 * error.translation().norm());
    if (error.translation().norm() > kEdgeToleranceM ||
        so3_log(error.quaternion()).norm() > kEdgeToleranceRad) {
      ++wrong[k];
      std::printf("  wrong %s edge: keyframe at %.3f s to the one at %.3f s (%.1f cm, %.2f deg)\n",
                  edge_kind_name(e.kind), from->second, to->second,
                  100 * error.translation().norm(),
                  so3_log(error.quaternion()).norm() * 180 / M_PI);
    }
    if (std::fabs(from->second - to->second) > kRevisitGapS) {
      joined_to_older[from->second > to->second ? e.from_id : e.to_id] = true;
    }
  }
  check_corrections(recorder, keyframe_s, gt);
  // Recall over the keyframes that revisit.
  int revisits = 0, found = 0;
  for (auto i = keyframe_s.begin(); i != keyframe_s.end(); ++i) {
    SE3 T_i;
    if (!truth_at(gt, i->second, &T_i)) continue;
    bool revisit = false;
    for (auto j = keyframe_s.begin(); j != keyframe_s.end() && !revisit; ++j) {
      SE3 T_j;
      if (i->second - j->second <= kRevisitGapS || !truth_at(gt, j->second, &T_j)) continue;
      const SE3 d = T_j.inverse() * T_i;
      revisit = d.translation().norm() < kRevisitDistanceM &&
                so3_log(d.quaternion()).norm() < kRevisitAngleRad;
    }
    revisits += revisit;
    found += revisit && joined_to_older.count(i->first) > 0;
  }
  const TrackingCounters& c = job.counters();
  std::printf(
      "live: ATE %.2f cm, coverage %.1f %%, false-valid %d of %d; final map: ATE %.2f cm, "
      "coverage %.1f %%\n",
      100 * live.ate.rmse_m, 100 * live.coverage.fraction(), live.false_valid.count,
      live.false_valid.checked, 100 * final_map.ate.rmse_m, 100 * final_map.coverage.fraction());
  std::printf(
      "events: %u lost, %u restarts, %u relocalised, %u loop corrections, %u withheld; %zu "
      "keyframes, %u reused\n",
      c.lost, c.resets, c.relocalised, c.loop_corrections, c.withheld, keyframe_s.size(), c.reused);
  // The stores' policies at work: what they forgot, and that no forgotten record was used.
  if (job.loop_enabled()) {
    std::printf(
        "stores: %u places remembered, the store keeps %d: %u forgotten (%.1f wraps); the dense "
        "pool keeps %d: %d recycled; stale handles refused: %u place, %u dense keyframe; %u "
        "relocalised at places older than the dense pool\n",
        job.loop().counters().keyframes, places.capacity(), places.evicted(),
        static_cast<double>(places.evicted()) / places.capacity(), pool.capacity(), pool.recycled(),
        places.stale_lookups(), pool.stale_lookups(), c.relocalised_past_the_pool);
  }
  if (full_frame > 0) {
    std::printf(
        "resident memory: %.1f MB after init, %.1f MB when both stores were first full (frame %d), "
        "%.1f MB after %d frames, of which %.1f MB is this bench's own growing record of the run\n",
        init_mb, full_mb, full_frame, end_mb, frames, end_records_mb - full_records_mb);
  } else {
    std::printf(
        "resident memory: %.1f MB after init, %.1f MB after %d frames (the stores never "
        "filled)\n",
        init_mb, end_mb, frames);
  }
  for (const Outage& o : outages) {
    const char* how = (o.flags & kRelocalised) != 0 ? "relocalised"
                      : (o.flags & kReset) != 0     ? "restarted"
                                                    : "tracked";
    if (o.frames_to_valid < 0) {
      std::printf("outage of %.2f s: no valid pose after it\n", o.gap_s);
    } else {
      std::printf("outage of %.2f s: valid %d frames after it (%s)\n", o.gap_s, o.frames_to_valid,
                  how);
    }
  }
  int all = 0, all_wrong = 0;
  std::printf("edges:");
  for (int k = 0; k < kEdgeKinds; ++k) {
    std::printf(" %s %d (%d wrong, median %.2f cm)", edge_kind_name(static_cast<EdgeKind>(k)),
                edges[k], wrong[k], median(error_cm[k]));
    all += edges[k];
    all_wrong += wrong[k];
  }
  std::printf("; %d without ground truth\n", unknown);
  std::printf(
      "revisits: recall %d of %d revisiting keyframes (%.1f %%); precision %.1f %% (%d of %d "
      "edges right)\n",
      found, revisits, revisits > 0 ? 100.0 * found / revisits : 0.0,
      all > 0 ? 100.0 * (all - all_wrong) / all : 100.0, all - all_wrong, all);
  const LatencyStats& search = job.loop().search_time();
  std::printf(
      "loop module ms per keyframe: describe median %.1f; search and verification median "
      "%.1f, p95 %.1f, max %.1f; pose graph max %.1f\n",
      job.loop().describe_time().percentile_ms(0.5), search.percentile_ms(0.5),
      search.percentile_ms(0.95), search.max_ms(), job.loop().optimise_time().max_ms());
  if (!row.empty()) {
    // sequence | keyframes | revisiting | found | recall | graph edges besides odometry |
    // wrong | precision | live ATE | final ATE | coverage | false-valid
    const int extra = all - edges[static_cast<int>(EdgeKind::kOdometry)];
    std::printf(
        "| %s | %zu | %d | %d | %.0f %% | %d | %d | %.1f %% | %.2f | %.2f | %.1f %% | %d |\n",
        row.c_str(), keyframe_s.size(), revisits, found,
        revisits > 0 ? 100.0 * found / revisits : 0.0, extra, all_wrong,
        all > 0 ? 100.0 * (all - all_wrong) / all : 100.0, 100 * live.ate.rmse_m,
        100 * final_map.ate.rmse_m, 100 * live.coverage.fraction(), live.false_valid.count);
  }
  return all_wrong == 0 ? 0 : 3;
}

// Place recognition by appearance alone, against the ground truth: every 5th frame queries the
// bag-of-words database of the frames more than 5 s before it; it is a revisit when one of them
// was within 15 cm and 20 degrees, and found when one of those is among the best k the query
// returns (k = 1, and 4 as the relocaliser asks for).
int bow_recall(const std::string& sequence, const Params& params) {
  Vocabulary voc;
  Status error;
  if (!load_vocabulary(params, &voc, &error)) {
    std::fprintf(stderr, "rgbdtam-loop-bench: %s\n", error.message());
    return 1;
  }
  std::vector<StampedPose> gt;
  int bad = 0;
  FrontendFrames frames;
  Status s = read_tum_trajectory((sequence + "/groundtruth.txt").c_str(), &gt, &bad);
  if (s.is_ok()) s = frames.open(sequence.c_str(), params);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam-loop-bench: %s\n", s.message());
    return 1;
  }
  PlaceRecognizer recognizer;
  recognizer.allocate(params);
  PlaceStore store;
  store.allocate(frames.count(), params.loop.features, voc.words(), params.camera);
  std::vector<SE3> poses;  // by keyframe id
  struct Older {
    const PlaceStore* store;
    int64_t before_ns;
  };
  auto older = [](const void* c, int slot) {
    const Older* o = static_cast<const Older*>(c);
    return o->store->at_slot(slot).timestamp_ns < o->before_ns;
  };
  constexpr int kTop = 4;
  int queries = 0, at_1 = 0, at_4 = 0;
  for (int i = 0; i < frames.count(); i += 5) {
    SE3 T;
    if (!truth_at(gt, frames.timestamp_ns(i) * 1e-9, &T) || !frames.load(i)) continue;
    const FramePyramid& frame = frames.frame();
    recognizer.describe(frame.gray(0), frame.inverse_depth(0), frame.intrinsics(0), voc);
    const int64_t t = frames.timestamp_ns(i);
    bool revisit = false;
    for (int k = 0; k < store.size() && !revisit; ++k) {
      const PlaceRecord& p = store.in_order(k);
      const SE3 d = poses[p.keyframe_id].inverse() * T;
      revisit = t - p.timestamp_ns > 5'000'000'000 && d.translation().norm() < kRevisitDistanceM &&
                so3_log(d.quaternion()).norm() < kRevisitAngleRad;
    }
    if (revisit) {
      const Older filter{&store, t - 5'000'000'000};
      PlaceMatch m[kTop];
      const int n = store.database().query(recognizer.bow(), older, &filter, m, kTop);
      for (int k = 0; k < n; ++k) {
        const SE3 d = poses[store.at_slot(m[k].slot).keyframe_id].inverse() * T;
        if (d.translation().norm() < kRevisitDistanceM &&
            so3_log(d.quaternion()).norm() < kRevisitAngleRad) {
          at_1 += k == 0;
          ++at_4;
          break;
        }
      }
      ++queries;
    }
    PlaceRecord* r = store.begin_insert();
    r->keyframe_id = static_cast<uint32_t>(poses.size());
    r->timestamp_ns = t;
    for (const Feature& f : recognizer.features()) (void)r->features.push_back(f);
    for (const BowEntry& e : recognizer.bow()) (void)r->bow.push_back(e);
    store.commit();
    poses.push_back(T);
  }
  std::printf(
      "%s with %s: %d revisiting frames; the best place a revisit in %.1f %%, one of the "
      "best %d in %.1f %%\n",
      sequence.c_str(), params.loop.vocabulary, queries, queries > 0 ? 100.0 * at_1 / queries : 0.0,
      kTop, queries > 0 ? 100.0 * at_4 / queries : 0.0);
  return 0;
}

double pose_graph_ms(int n) {
  // A chain that drifts 0.5 degrees a step, each keyframe aligned with the one two before it
  // (a covisible edge), closed by a loop every 16 keyframes: about 2 edges a keyframe.
  PoseGraph g;
  g.allocate(n, 3 * n);
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
    if (i >= 2) g.add_edge(i - 2, i, truth[i - 2].inverse() * truth[i], 1e3 * Matrix6d::Identity());
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
  store.allocate(params.loop.places, params.loop.features, voc.words(), params.camera);
  std::vector<double> describe_ms;
  std::vector<std::vector<Feature>> features;
  std::vector<std::vector<BowEntry>> bows;
  std::vector<View> views;
  for (int i = 0; i < frames.count(); i += 20) {
    if (!frames.load(i)) continue;
    const FramePyramid& frame = frames.frame();
    const int64_t t0 = monotonic_ns();
    recognizer.describe(frame.gray(0), frame.inverse_depth(0), frame.intrinsics(0), voc);
    describe_ms.push_back((monotonic_ns() - t0) * 1e-6);
    features.emplace_back(recognizer.features().begin(), recognizer.features().end());
    bows.emplace_back(recognizer.bow().begin(), recognizer.bow().end());
    views.emplace_back();
    views.back().allocate(params.camera);
    capture_view(frame, &views.back());
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
  std::vector<double> query_ms, verify_ms, align_ms;
  const VerificationLimits limits = VerificationLimits::of(params);
  ViewAligner aligner;
  aligner.allocate(params.camera, params.sensor.depth_factor, params.sensor.depth_range,
                   tracking_options(params));
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
    // A candidate's view against the keyframe's, both ways, from the neighbour's pose.
    const int64_t t2 = monotonic_ns();
    aligner.set(0, views[(k + 1) % views.size()]);
    aligner.set(1, views[k]);
    const SE3 guess;
    (void)aligner.align(&guess, 1, health_limits(params));
    align_ms.push_back((monotonic_ns() - t2) * 1e-6);
  }
  std::printf(
      "query of %d places: median %.2f ms; a first guess by features (match + RANSAC): median "
      "%.2f ms; one view alignment, both ways (the verification): median %.2f ms, max %.2f ms\n",
      store.capacity(), median(query_ms), median(verify_ms), median(align_ms),
      *std::max_element(align_ms.begin(), align_ms.end()));
  std::printf(
      "pose graph, 10 Gauss-Newton steps: 32 keyframes %.2f ms, 256 %.2f ms, 1024 %.1f ms\n",
      pose_graph_ms(32), pose_graph_ms(256), pose_graph_ms(1024));
  std::printf(
      "light store at capacity (%d places of %d features and a view each, with its index): "
      "%.1f MB\n",
      params.loop.places, params.loop.features,
      PlaceStore::bytes_needed(params.loop.places, params.loop.features, voc.words(),
                               params.camera) /
          1048576.0);
  return 0;
}

}  // namespace
}  // namespace rgbdtam

int main(int argc, char** argv) {
  using namespace rgbdtam;
  const bool views = argc >= 3 && std::strcmp(argv[1], "views") == 0;
  const bool bow = argc >= 3 && std::strcmp(argv[1], "bow") == 0;
  if (argc < 3 || (std::strcmp(argv[1], "replay") != 0 && std::strcmp(argv[1], "costs") != 0 &&
                   !views && !bow)) {
    std::fprintf(stderr,
                 "usage: rgbdtam-loop-bench replay|costs <sequence> --config <file> "
                 "[--set key=value]... [--row <label>]\n"
                 "       rgbdtam-loop-bench bow <sequence> --config <file> [--set key=value]...\n"
                 "       rgbdtam-loop-bench views <sequence> --config <file> [--every <n>] "
                 "[--stranger <sequence> --stranger-config <file>]\n");
    return 2;
  }
  Params params, stranger_params;
  std::string stranger, row;
  int every = 10;
  bool have_config = false;
  for (int i = 3; i < argc; ++i) {
    Status s;
    if (std::strcmp(argv[i], "--config") == 0 && i + 1 < argc) {
      s = read_params_file(argv[++i], &params);
      have_config = true;
    } else if (std::strcmp(argv[i], "--set") == 0 && i + 1 < argc) {
      s = set_param(argv[++i], "--set", &params);
    } else if (std::strcmp(argv[i], "--row") == 0 && i + 1 < argc) {
      row = argv[++i];
    } else if (views && std::strcmp(argv[i], "--every") == 0 && i + 1 < argc) {
      every = std::max(1, std::atoi(argv[++i]));
    } else if (views && std::strcmp(argv[i], "--stranger") == 0 && i + 1 < argc) {
      stranger = argv[++i];
    } else if (views && std::strcmp(argv[i], "--stranger-config") == 0 && i + 1 < argc) {
      s = read_params_file(argv[++i], &stranger_params);
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
  if (views) return view_study(argv[2], params, stranger, stranger_params, every);
  if (bow) return bow_recall(argv[2], params);
  return std::strcmp(argv[1], "replay") == 0 ? replay(argv[2], params, row)
                                             : costs(argv[2], params);
}

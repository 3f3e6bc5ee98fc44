#include "rgbdtam/runtime/loop_closing.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rgbdtam/runtime/map_checkpoint.hpp"

namespace rgbdtam {
namespace {
constexpr int kGaussNewtonSteps = 10;
// Places this few edges away are the keyframe's covisible neighbourhood: odometry and the
// neighbours' edges already tie them to it, so a revisit is a place the graph reaches only
// through a longer path (along which drift accumulates), or not at all.
constexpr int kCovisibleHops = 3;
// A place the map puts this near the keyframe may show the same scene (direct alignment then
// decides): the views of pairs further apart rarely overlap by half.
constexpr double kNearM = 0.4;
constexpr double kNearRad = 30.0 * M_PI / 180.0;
// A relation the map does not know (a restart's jump): in the graph for connectedness only.
constexpr double kUnknownRelationInformation = 1e-6;

struct QueryFilter {
  const int* hops;
};

bool outside_neighbourhood(const void* context, int slot) {
  const int h = static_cast<const QueryFilter*>(context)->hops[slot];
  return h < 0 || h > kCovisibleHops;
}

}  // namespace

const char* edge_kind_name(EdgeKind kind) {
  switch (kind) {
    case EdgeKind::kOdometry:
      return "odometry";
    case EdgeKind::kRestart:
      return "restart";
    case EdgeKind::kRelocalisation:
      return "relocalisation";
    case EdgeKind::kCovisible:
      return "covisible";
    case EdgeKind::kRevisit:
      return "revisit";
    case EdgeKind::kReuse:
      return "reuse";
  }
  return "?";
}

void LoopQueue::allocate(int slots, const PinholeIntrinsics& camera) {
  SpscRing<LoopKeyframe>::allocate(slots);
  for (int i = 0; i < slots; ++i) {
    slot(i).gray.allocate(camera.width_px, camera.height_px);
    slot(i).inverse_depth.allocate(camera.width_px, camera.height_px);
    slot(i).view.allocate(camera);
  }
}

void CorrectionQueue::allocate(int slots, int places) {
  SpscRing<LoopCorrection>::allocate(slots);
  for (int i = 0; i < slots; ++i) slot(i).poses.reserve_once(places);
}

size_t LoopModule::bytes_needed(const Params& p) {
  const size_t places = static_cast<size_t>(p.loop.places);
  const size_t edges = places * kEdgesPerPlace;
  constexpr size_t kGraphBytesPerNode = 3 * sizeof(Matrix6d) + 6 * sizeof(Vector6d) + sizeof(SE3);
  constexpr size_t kGraphBytesPerEdge = 2 * sizeof(Matrix6d) + sizeof(SE3) + 16;
  return places * (kGraphBytesPerNode + 5 * sizeof(int) + sizeof(uint8_t)) +
         edges * (sizeof(Edge) + kGraphBytesPerEdge + 2 * sizeof(int)) +
         ViewAligner::bytes_needed(p.camera, tracking_options(p));
}

Status LoopModule::init(const Params& params, const Vocabulary* vocabulary, PlaceStore* store,
                        CorrectionQueue* corrections, ClockFn clock) {
  params_ = params;
  params_.health = health_limits(params);
  vocabulary_ = vocabulary;
  store_ = store;
  corrections_ = corrections;
  clock_ = clock;
  recognizer_.allocate(params);
  limits_ = VerificationLimits::of(params);
  aligner_.allocate(params.camera, params.sensor.depth_factor, params.sensor.depth_range,
                    tracking_options(params));
  const int places = params.loop.places;
  const int edges = places * kEdgesPerPlace;
  graph_.allocate(places, edges);
  edges_.reserve_once(edges);
  for (auto* a : {&hops_, &queue_, &node_of_slot_}) a->reset(new int[static_cast<size_t>(places)]);
  after_restart_.reset(new uint8_t[static_cast<size_t>(places)]());
  first_neighbour_.reset(new int[static_cast<size_t>(places) + 1]);
  neighbours_.reset(new int[2 * static_cast<size_t>(edges)]);
  return Status::ok();
}

void LoopModule::step(const LoopKeyframe& message) {
  if (message.kind == LoopKeyframe::Kind::kReuse) {
    add_reuse(message);
  } else {
    add_keyframe(message);
  }
  if (checkpoint_ != nullptr) checkpoint_->changed();
}

void LoopModule::tick() {
  if (checkpoint_ != nullptr) checkpoint_->save_if_due(*store_, edges_);
}

void LoopModule::add_keyframe(const LoopKeyframe& keyframe) {
  const int64_t t0 = clock_();
  // A keyframe made before the tracker adopted the last correction is in the old frame.
  SE3 T_w_k = keyframe.T_w_k;
  if (keyframe.corrections_adopted < corrections_sent_) T_w_k = last_correction_ * T_w_k;
  recognizer_.describe(keyframe.gray, keyframe.inverse_depth, params_.camera, *vocabulary_);
  const int64_t t1 = clock_();
  describe_time_.add(t1 - t0);
  remember(keyframe, T_w_k);
  const int query = store_->size() - 1;
  const PlaceHandle query_handle = store_->handle(query);
  // The tracker's own measurement; a keyframe whose reference the map does not hold (forgotten,
  // or left out at a full queue) hangs on its predecessor with no information, for connectedness.
  int reference = store_->order_of(keyframe.reference_id);
  EdgeKind measured = keyframe.reference_edge;
  if (reference < 0 || reference == query) {
    reference = query - 1;
    measured = EdgeKind::kRestart;
  }
  after_restart_[query_handle.slot] = measured == EdgeKind::kRestart;
  if (reference >= 0) {
    // Its pose came from this measurement, so the map agrees with it.
    const bool known = measured != EdgeKind::kRestart;
    const SE3 T_ref_k =
        known ? keyframe.T_reference_keyframe : store_->in_order(reference).T_w_k.inverse() * T_w_k;
    (void)add_edge(
        {store_->handle(reference), query_handle, T_ref_k,
         known ? keyframe.information : kUnknownRelationInformation * Matrix6d::Identity(),
         measured});
  }
  bool correct = false;
  measure_hops(query_handle.slot);
  // The local window: the tracker's further measurements, against earlier keyframes a few
  // measured edges away, refine the map at smaller disagreements than a revisit corrects it.
  // Further away, or across a restart, one would close a loop unverified; on an image that
  // repeats, it may be a period off.
  bool refine = false;
  for (int i = 0; i < keyframe.window_edges && !keyframe.repeats; ++i) {
    const WindowEdge& w = keyframe.window[i];
    const int window = store_->order_of(w.window_id);
    if (window < 0) continue;
    const PlaceHandle window_handle = store_->handle(window);
    const int hops = hops_[window_handle.slot];
    if (hops >= 2 && hops <= kCovisibleHops && !store_->at_slot(window_handle.slot).repeats) {
      refine |= add_edge(
          {window_handle, query_handle, w.T_window_keyframe, w.information, EdgeKind::kCovisible},
          window_limit());
      ++counters_.window_edges;
      measure_hops(query_handle.slot);  // the window's place is now a neighbour, not a candidate
    }
  }
  PlaceCandidate candidates[CandidateBudget::kTotal];
  // A keyframe whose image repeats along a surface does not say where along it a match is.
  const int n = keyframe.repeats ? 0 : choose_candidates(query_handle.slot, candidates);
  aligner_.set(1, keyframe.view);
  // Verified first: revisits that put the keyframe in places further apart than a jump the
  // map would report are a repeated scene (panels, tiles), not a loop, and none of them is kept.
  Edge verified[CandidateBudget::kTotal];
  int m = 0;
  bool revisits_agree = true;
  const Edge* first_revisit = nullptr;
  for (int i = 0; i < n; ++i) {
    const PlaceRecord& record = store_->at_slot(candidates[i].slot);
    if (record.repeats) continue;
    ++counters_.candidates;
    aligner_.set(0, record.view);
    const ViewAlignment a =
        aligner_.align(candidates[i].guesses, candidates[i].guess_count, params_.health);
    if (!measures_pose(a)) continue;
    const Matrix6d information =
        graph_information(a.forward.information / params_.covariance_scale, a.T_a_b);
    verified[m] = {PlaceHandle{candidates[i].slot, record.generation}, query_handle, a.T_a_b,
                   information, candidates[i].kind};
    if (candidates[i].kind == EdgeKind::kRevisit && !within_drift(candidates[i].slot, query, a)) {
      // The two only look alike: neither is a place to be found at again.
      std::lock_guard<std::mutex> lock(store_->mutex());
      store_->mark_repeats(candidates[i].slot);
      store_->mark_repeats(query_handle.slot);
      ++counters_.look_alikes;
      continue;
    }
    if (candidates[i].kind == EdgeKind::kRevisit) {
      if (first_revisit == nullptr) {
        first_revisit = &verified[m];
      } else {
        const SE3 d =
            (store_->get(first_revisit->from)->T_w_k * first_revisit->T_from_to).inverse() *
            (record.T_w_k * a.T_a_b);
        revisits_agree = revisits_agree && within(d, params_.loop.max_reported_jump_m,
                                                  params_.loop.max_reported_jump_rad);
      }
    }
    ++m;
  }
  if (!revisits_agree) ++counters_.revisits_disagreeing;
  for (int i = 0; i < m; ++i) {
    const bool revisit = verified[i].kind == EdgeKind::kRevisit;
    if (revisit && !revisits_agree) continue;
    const bool disagrees = add_edge(verified[i]);
    // A neighbour's edge refines the map at the next optimisation; a revisit corrects it.
    correct |= disagrees && revisit;
    ++(revisit ? counters_.revisit_edges : counters_.covisible_edges);
  }
  search_time_.add(clock_() - t1);
  if (correct) {
    optimise(correction_limit());
  } else if (refine) {
    optimise(window_limit());
  }
}

bool LoopModule::within_drift(int place_slot, int query, const ViewAlignment& a) const {
  const PlaceRecord& place = store_->at_slot(place_slot);
  const PlaceRecord& latest = store_->in_order(query);
  // The distance travelled between them, along the places in between (the earlier place may be
  // gone from the order: then from the oldest place kept).
  int from = store_->order_of(place.keyframe_id);
  if (from < 0) from = 0;
  double travelled = 0.0;
  for (int i = from; i < query; ++i) {
    if (after_restart_[store_->handle(i + 1).slot]) return true;
    travelled +=
        (store_->in_order(i + 1).T_w_k.translation() - store_->in_order(i).T_w_k.translation())
            .norm();
  }
  const SE3 correction = (place.T_w_k * a.T_a_b).inverse() * latest.T_w_k;
  return correction.translation().norm() <= params_.loop.max_drift_ratio * travelled + kSamePoseM;
}

void LoopModule::add_reuse(const LoopKeyframe& message) {
  const int from = store_->order_of(message.reference_id);
  const int to = store_->order_of(message.keyframe_id);
  if (from < 0 || to < 0 || from == to) return;
  ++counters_.reuse_edges;
  if (add_edge({store_->handle(from), store_->handle(to), message.T_reference_keyframe,
                message.information, EdgeKind::kReuse})) {
    optimise(correction_limit());
  }
}

void LoopModule::remember(const LoopKeyframe& keyframe, const SE3& T_w_k) {
  std::lock_guard<std::mutex> lock(store_->mutex());
  PlaceRecord* r = store_->begin_insert();
  r->keyframe_id = keyframe.keyframe_id;
  r->timestamp_ns = keyframe.timestamp_ns;
  r->T_w_k = T_w_k;
  r->repeats = keyframe.repeats;
  for (const Feature& f : recognizer_.features()) (void)r->features.push_back(f);
  for (const BowEntry& e : recognizer_.bow()) (void)r->bow.push_back(e);
  std::memcpy(r->view.gray.data(), keyframe.view.gray.data(), keyframe.view.gray.size());
  std::memcpy(r->view.inverse_depth.data(), keyframe.view.inverse_depth.data(),
              sizeof(uint16_t) * static_cast<size_t>(keyframe.view.inverse_depth.size()));
  store_->commit();
  ++counters_.keyframes;
}

bool LoopModule::add_edge(const Edge& edge, const MoveLimit& limit) {
  if (edges_.size() == edges_.capacity()) {
    // Full: forget the edges of forgotten places.
    int kept = 0;
    for (const Edge& e : edges_) {
      if (store_->get(e.from) != nullptr && store_->get(e.to) != nullptr) edges_[kept++] = e;
    }
    edges_.truncate(kept);
  }
  if (!edges_.push_back(edge)) {
    ++counters_.edges_dropped;
    return false;
  }
  const PlaceRecord* from = store_->get(edge.from);
  const PlaceRecord* to = store_->get(edge.to);
  if (observer_ != nullptr) {
    observer_->on_edge({from->keyframe_id, to->keyframe_id, edge.T_from_to, edge.kind});
  }
  if (edge.kind == EdgeKind::kRestart) return false;
  return limit.exceeded_by((from->T_w_k * edge.T_from_to).inverse() * to->T_w_k);
}

void LoopModule::measure_hops(int slot) {
  const int places = store_->capacity();
  int* degree = hops_.get();  // reused as the fill cursor before the search
  std::fill(degree, degree + places, 0);
  auto usable = [&](const Edge& e) {
    return e.kind != EdgeKind::kRestart && store_->get(e.from) != nullptr &&
           store_->get(e.to) != nullptr;
  };
  for (const Edge& e : edges_) {
    if (!usable(e)) continue;
    ++degree[e.from.slot];
    ++degree[e.to.slot];
  }
  first_neighbour_[0] = 0;
  for (int i = 0; i < places; ++i) first_neighbour_[i + 1] = first_neighbour_[i] + degree[i];
  for (int i = 0; i < places; ++i) degree[i] = first_neighbour_[i];
  for (const Edge& e : edges_) {
    if (!usable(e)) continue;
    neighbours_[degree[e.from.slot]++] = e.to.slot;
    neighbours_[degree[e.to.slot]++] = e.from.slot;
  }
  std::fill(hops_.get(), hops_.get() + places, -1);
  int head = 0, tail = 0;
  hops_[slot] = 0;
  queue_[tail++] = slot;
  while (head < tail) {
    const int s = queue_[head++];
    for (int k = first_neighbour_[s]; k < first_neighbour_[s + 1]; ++k) {
      const int t = neighbours_[k];
      if (hops_[t] >= 0) continue;
      hops_[t] = hops_[s] + 1;
      queue_[tail++] = t;
    }
  }
}

int LoopModule::choose_candidates(int query_slot, PlaceCandidate* out) {
  const PlaceRecord& q = store_->at_slot(query_slot);
  const SE3 T_q_w = q.T_w_k.inverse();
  // By geometry: the nearest covisible place that is not yet a neighbour, and the revisits the
  // graph joins through the longest paths.
  struct Ranked {
    int slot = -1;
    int hops = 0;
    double distance = 0.0;
  };
  Ranked covisible;
  Ranked revisits[CandidateBudget::kGeometric];
  int revisit_count = 0;
  for (int i = 0; i < store_->size(); ++i) {
    const int slot = store_->handle(i).slot;
    // A place the graph does not join (before a restart, which began at the last valid pose,
    // so the map's guess still holds roughly) is the longest loop of all.
    const SE3 d = T_q_w * store_->at_slot(slot).T_w_k;
    const Ranked r{slot, hops_[slot] < 0 ? store_->capacity() : hops_[slot], ranking_distance_m(d)};
    if (r.hops < 2) continue;  // itself and its neighbours
    if (!within(d, kNearM, kNearRad)) continue;
    if (r.hops <= kCovisibleHops) {
      if (covisible.slot < 0 || r.distance < covisible.distance) covisible = r;
      continue;
    }
    // Kept sorted: the most hops first, then the nearest.
    auto before = [](const Ranked& a, const Ranked& b) {
      return a.hops != b.hops ? a.hops > b.hops : a.distance < b.distance;
    };
    int at = revisit_count;
    while (at > 0 && before(r, revisits[at - 1])) --at;
    if (at == CandidateBudget::kGeometric) continue;
    revisit_count = std::min(revisit_count + 1, CandidateBudget::kGeometric);
    for (int k = revisit_count - 1; k > at; --k) revisits[k] = revisits[k - 1];
    revisits[at] = r;
  }
  int n = 0;
  auto map_guess = [&](int slot) { return store_->at_slot(slot).T_w_k.inverse() * q.T_w_k; };
  auto add = [&](int slot, EdgeKind kind) {
    PlaceCandidate& c = out[n++];
    c = PlaceCandidate();
    c.slot = slot;
    c.kind = kind;
    c.add_guess(map_guess(slot));
    return &c;
  };
  if (covisible.slot >= 0) add(covisible.slot, EdgeKind::kCovisible);
  for (int i = 0; i < revisit_count; ++i) {
    add(revisits[i].slot, EdgeKind::kRevisit)->add_guess(SE3());  // or where the place was seen
  }
  // By appearance, outside the neighbourhood: the features' fit is the first guess, then the
  // map's, then the place's own pose.
  const int first = n;
  {
    std::lock_guard<std::mutex> lock(store_->mutex());
    const QueryFilter filter{hops_.get()};
    n = recognizer_.add_appearance_candidates(*store_, outside_neighbourhood, &filter,
                                              CandidateBudget::kAppearance, limits_, out, n);
  }
  for (int i = first; i < n; ++i) {
    out[i].add_guess(map_guess(out[i].slot));
    out[i].add_guess(SE3());
  }
  return n;
}

bool LoopModule::MoveLimit::exceeded_by(const SE3& d) const { return !within(d, m, rad); }

LoopModule::MoveLimit LoopModule::correction_limit() const {
  return {params_.loop.min_correction_m, params_.loop.min_correction_rad};
}

LoopModule::MoveLimit LoopModule::window_limit() const {
  return {params_.loop.min_window_correction_m, params_.loop.min_window_correction_rad};
}

void LoopModule::optimise(const MoveLimit& send_beyond) {
  const int64_t t0 = clock_();
  graph_.clear();
  graph_.set_fixed(store_->kept());  // a map localised in stays as it was saved
  const int n = store_->size();
  for (int i = 0; i < n; ++i) {
    node_of_slot_[store_->handle(i).slot] = graph_.add_node(store_->in_order(i).T_w_k);
  }
  for (const Edge& e : edges_) {
    if (store_->get(e.from) == nullptr || store_->get(e.to) == nullptr) continue;
    (void)graph_.add_edge(node_of_slot_[e.from.slot], node_of_slot_[e.to.slot], e.T_from_to,
                          e.information);
  }
  (void)graph_.optimize(kGaussNewtonSteps);
  // Sent only when it moves the map: each correction resets the consumers' estimate.
  bool moved = false;
  for (int i = 0; i < n && !moved; ++i) {
    moved = send_beyond.exceeded_by(store_->in_order(i).T_w_k.inverse() * graph_.pose(i));
  }
  LoopCorrection* out = moved ? corrections_->begin_push() : nullptr;
  if (moved && out == nullptr)
    ++counters_.corrections_dropped;  // the map stays as the tracker knows it
  if (out == nullptr) {
    optimise_time_.add(clock_() - t0);
    return;
  }
  out->poses.clear();
  {
    std::lock_guard<std::mutex> lock(store_->mutex());
    const SE3 newest_before = store_->in_order(n - 1).T_w_k;
    for (int i = 0; i < n; ++i) {
      PlaceRecord& r = store_->in_order(i);
      if (observer_ != nullptr) {
        observer_->on_place_moved(counters_.corrections + 1, r.keyframe_id, r.T_w_k,
                                  graph_.pose(i));
      }
      r.T_w_k = graph_.pose(i);
      (void)out->poses.push_back({r.keyframe_id, r.T_w_k});
    }
    last_correction_ = graph_.pose(n - 1) * newest_before.inverse();
  }
  ++corrections_sent_;
  ++counters_.corrections;
  corrections_->publish();
  optimise_time_.add(clock_() - t0);
}

}  // namespace rgbdtam

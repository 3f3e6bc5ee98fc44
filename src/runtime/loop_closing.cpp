#include "rgbdtam/runtime/loop_closing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace rgbdtam {
namespace {
constexpr int kCandidates = 3;             // best-scoring places verified per query
constexpr double kMinRelativeScore = 0.5;  // ... when within this fraction of the best score
constexpr int kConsistentOrderGap = 4;     // "the same place": records this close in the store
constexpr int kGaussNewtonSteps = 10;
// A relation the map does not know (a restart's jump): in the graph for connectedness only.
constexpr double kUnknownRelationInformation = 1e-6;
// Spread of the matched points about their centroid, for the loop edge's rotation, m.
constexpr double kMatchSpreadM = 0.5;
constexpr double kMinMatchRmsM = 0.01;

struct CandidateFilter {
  const PlaceStore* store;
  uint32_t segment;
  int64_t timestamp_ns;
  int64_t min_age_ns;
};

bool is_loop_candidate(const void* context, int slot) {
  const auto* f = static_cast<const CandidateFilter*>(context);
  const PlaceRecord& r = f->store->at_slot(slot);
  return r.segment != f->segment || f->timestamp_ns - r.timestamp_ns >= f->min_age_ns;
}

// The tracker's information of a keyframe's pose relative to its reference, moved from the
// reference side (how the tracker perturbs) to the keyframe side (how the graph perturbs).
Matrix6d edge_information(const PlaceRecord& r, const SE3& T_ref_k) {
  if (r.information.isZero()) return kUnknownRelationInformation * Matrix6d::Identity();
  const Matrix6d A = adjoint(T_ref_k);
  return A.transpose() * r.information * A;
}
}  // namespace

void LoopQueue::allocate(int slots, int width, int height) {
  SpscRing<LoopKeyframe>::allocate(slots);
  for (int i = 0; i < slots; ++i) {
    slot(i).gray.allocate(width, height);
    slot(i).inverse_depth.allocate(width, height);
  }
}

void CorrectionQueue::allocate(int slots, int places) {
  SpscRing<LoopCorrection>::allocate(slots);
  for (int i = 0; i < slots; ++i) slot(i).poses.reserve_once(places);
}

Status LoopModule::init(const Params& params, const Vocabulary* vocabulary, PlaceStore* store,
                        CorrectionQueue* corrections, ClockFn clock) {
  params_ = params;
  vocabulary_ = vocabulary;
  store_ = store;
  corrections_ = corrections;
  clock_ = clock;
  recognizer_.allocate(params);
  limits_ = VerificationLimits::of(params);
  graph_.allocate(params.loop.places, 2 * params.loop.places);
  loops_.reserve_once(params.loop.places);
  return Status::ok();
}

void LoopModule::step(const LoopKeyframe& keyframe) {
  const int64_t t0 = clock_();
  // A keyframe made before the tracker adopted the last correction is in the old frame.
  SE3 T_w_k = keyframe.T_w_k;
  if (keyframe.corrections_adopted < corrections_sent_) T_w_k = last_correction_ * T_w_k;
  recognizer_.describe(keyframe.gray, keyframe.inverse_depth, params_.camera, *vocabulary_);
  const int64_t t1 = clock_();
  describe_time_.add(t1 - t0);
  segment_ += keyframe.after_reset ? 1 : 0;
  Found found;
  const bool loop = detect(keyframe, &found);
  query_time_.add(clock_() - t1);
  remember(keyframe, T_w_k);
  if (loop) close_loop(found, keyframe.keyframe_id);
}

bool LoopModule::detect(const LoopKeyframe& query, Found* found) {
  const CandidateFilter filter{store_, segment_, query.timestamp_ns,
                               static_cast<int64_t>(params_.loop.min_age_s * 1e9)};
  PlaceMatch matches[kCandidates];
  PlaceMatchEvent events[kCandidates];
  int verified = 0;
  int n = 0;
  {
    // A query uses the database's scratch, which a relocalising tracker uses too. The records
    // themselves only this thread writes, so it reads them without the lock.
    std::lock_guard<std::mutex> lock(store_->mutex());
    n = store_->database().query(recognizer_.bow(), is_loop_candidate, &filter, matches,
                                 kCandidates);
  }
  for (int i = 0; i < n && matches[i].score >= kMinRelativeScore * matches[0].score; ++i) {
    const PlaceRecord& place = store_->at_slot(matches[i].slot);
    ++counters_.candidates;
    const RigidRansacResult fit = recognizer_.verify(place, limits_);
    if (fit.inliers == 0) continue;
    events[verified++] = {query.keyframe_id,
                          place.keyframe_id,
                          query.timestamp_ns,
                          place.timestamp_ns,
                          fit.T_b_a,
                          fit.inliers,
                          false};
    if (verified > 1 && fit.inliers <= found->fit.inliers) continue;
    found->place = {matches[i].slot, place.generation};
    found->keyframe_id = place.keyframe_id;
    found->T_place_query = fit.T_b_a;
    found->fit = fit;
  }
  bool loop = false;
  if (verified == 0) {
    consistent_ = 0;
  } else {
    ++counters_.verified;
    const int order = store_->order_of(found->keyframe_id);
    const int last = store_->order_of(last_match_id_);
    const bool same_place =
        consistent_ > 0 && last >= 0 && std::abs(order - last) <= kConsistentOrderGap;
    consistent_ = same_place ? consistent_ + 1 : 1;
    last_match_id_ = found->keyframe_id;
    loop = consistent_ >= params_.loop.consistent_queries;
  }
  for (int i = 0; observer_ != nullptr && i < verified; ++i) {
    events[i].loop = loop && events[i].place_id == found->keyframe_id;
    observer_->on_verified(events[i]);
  }
  return loop;
}

void LoopModule::remember(const LoopKeyframe& keyframe, const SE3& T_w_k) {
  std::lock_guard<std::mutex> lock(store_->mutex());
  PlaceRecord* r = store_->begin_insert();
  r->keyframe_id = keyframe.keyframe_id;
  r->segment = segment_;
  r->timestamp_ns = keyframe.timestamp_ns;
  r->T_w_k = T_w_k;
  r->reference_id = keyframe.reference_id;
  r->after_reset = keyframe.after_reset;
  r->information = keyframe.information;
  for (const Feature& f : recognizer_.features()) (void)r->features.push_back(f);
  for (const BowEntry& e : recognizer_.bow()) (void)r->bow.push_back(e);
  store_->commit();
  ++counters_.keyframes;
}

void LoopModule::close_loop(const Found& found, uint32_t query_id) {
  const PlaceRecord* place = store_->get(found.place);
  if (place == nullptr) return;  // evicted by the insertion just made
  const PlaceHandle query = store_->handle(store_->size() - 1);
  const PlaceRecord& q = store_->in_order(store_->size() - 1);
  if (loops_.size() == loops_.capacity()) {
    // Full: forget the loops whose places are gone.
    int kept = 0;
    for (const LoopEdge& e : loops_) {
      if (store_->get(e.from) != nullptr && store_->get(e.to) != nullptr) loops_[kept++] = e;
    }
    loops_.truncate(kept);
  }
  const double n = found.fit.inliers;
  const double rms = std::max(found.fit.rms_m, kMinMatchRmsM);
  Matrix6d information = Matrix6d::Zero();
  information.diagonal().head<3>().setConstant(n / (rms * rms));
  information.diagonal().tail<3>().setConstant(n * kMatchSpreadM * kMatchSpreadM / (rms * rms));
  if (!loops_.push_back({found.place, query, found.T_place_query, information})) return;
  ++counters_.loops;
  const SE3 disagreement = (place->T_w_k * found.T_place_query).inverse() * q.T_w_k;
  if (disagreement.translation().norm() < params_.loop.min_correction_m &&
      so3_log(disagreement.quaternion()).norm() < params_.loop.min_correction_rad) {
    return;
  }
  optimise(query_id, found.keyframe_id);
}

void LoopModule::optimise(uint32_t query_id, uint32_t match_id) {
  const int64_t t0 = clock_();
  graph_.clear();
  const int n = store_->size();
  for (int i = 0; i < n; ++i) (void)graph_.add_node(store_->in_order(i).T_w_k);
  for (int i = 1; i < n; ++i) {
    const PlaceRecord& r = store_->in_order(i);
    const int ref = r.after_reset ? -1 : store_->order_of(r.reference_id);
    const int from = ref >= 0 && ref != i ? ref : i - 1;
    const SE3 T_from_k = store_->in_order(from).T_w_k.inverse() * r.T_w_k;
    const Matrix6d information = r.after_reset ? kUnknownRelationInformation * Matrix6d::Identity()
                                               : edge_information(r, T_from_k);
    (void)graph_.add_edge(from, i, T_from_k, information);
  }
  auto order_of_handle = [&](const PlaceHandle& h) {
    const PlaceRecord* r = store_->get(h);
    return r == nullptr ? -1 : store_->order_of(r->keyframe_id);
  };
  for (const LoopEdge& e : loops_) {
    const int from = order_of_handle(e.from), to = order_of_handle(e.to);
    if (from >= 0 && to >= 0 && from != to)
      (void)graph_.add_edge(from, to, e.T_from_to, e.information);
  }
  (void)graph_.optimize(kGaussNewtonSteps);
  LoopCorrection* out = corrections_->begin_push();
  if (out == nullptr) {
    // The tracker has not taken the last one: the map stays as the tracker knows it.
    ++counters_.corrections_dropped;
    optimise_time_.add(clock_() - t0);
    return;
  }
  out->query_id = query_id;
  out->match_id = match_id;
  out->poses.clear();
  {
    std::lock_guard<std::mutex> lock(store_->mutex());
    const SE3 newest_before = store_->in_order(n - 1).T_w_k;
    for (int i = 0; i < n; ++i) {
      PlaceRecord& r = store_->in_order(i);
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

#include "rgbdtam/runtime/place_recognition.hpp"

#include <algorithm>
#include <cstring>

namespace rgbdtam {

void PlaceStore::allocate(int capacity, int features_per_place, int words,
                          const PinholeIntrinsics& camera) {
  capacity_ = capacity;
  records_.reset(new PlaceRecord[static_cast<size_t>(capacity)]);
  for (int i = 0; i < capacity; ++i) {
    records_[i].features.reserve_once(features_per_place);
    records_[i].bow.reserve_once(features_per_place);
    records_[i].view.allocate(camera);
  }
  database_.allocate(capacity, words, features_per_place);
}

size_t PlaceStore::bytes_needed(int capacity, int features_per_place, int words,
                                const PinholeIntrinsics& camera) {
  const size_t per_place =
      sizeof(PlaceRecord) +
      static_cast<size_t>(features_per_place) * (sizeof(Feature) + sizeof(BowEntry)) +
      View::bytes(camera);
  // The database: an entry per word of every place, and per-word list heads and scores.
  const size_t index = static_cast<size_t>(capacity) * features_per_place * 16 +
                       static_cast<size_t>(words) * 4 + static_cast<size_t>(capacity) * 12;
  return static_cast<size_t>(capacity) * per_place + index;
}

PlaceRecord* PlaceStore::begin_insert() {
  int slot;
  if (size_ == capacity_) {
    slot = first_;
    database_.remove(slot);
    first_ = kept_ + (first_ - kept_ + 1) % (capacity_ - kept_);
    --size_;
    evicted_.fetch_add(1, std::memory_order_relaxed);
  } else {
    slot = slot_of(size_);
  }
  PlaceRecord& r = records_[slot];
  ++r.generation;
  r.features.clear();
  r.bow.clear();
  r.repeats = false;
  return &r;
}

void PlaceStore::keep_oldest(int count) {
  RGBDTAM_ASSERT(count >= 0 && count < capacity_ && count <= size_ && first_ == kept_,
                 "the kept records are the oldest, with room for a ring after them");
  kept_ = count;
  first_ = count;
}

void PlaceStore::commit() {
  const int slot = slot_of(size_);
  database_.add(slot, records_[slot].bow);
  ++size_;
}

int PlaceStore::order_of(uint32_t keyframe_id) const {
  // Keyframe ids grow with insertion order.
  int lo = 0, hi = size_;
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (in_order(mid).keyframe_id < keyframe_id) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo < size_ && in_order(lo).keyframe_id == keyframe_id ? lo : -1;
}

PlaceHandle PlaceStore::handle(int order) const {
  const int slot = slot_of(order);
  return {slot, records_[slot].generation};
}

const PlaceRecord* PlaceStore::get(const PlaceHandle& h) const {
  if (h.slot < 0 || h.slot >= capacity_ || records_[h.slot].generation != h.generation) {
    stale_lookups_.fetch_add(1, std::memory_order_relaxed);
    return nullptr;
  }
  return &records_[h.slot];
}

size_t PlaceRecognizer::bytes_needed(const Params& params) {
  // The extractor's images (3 float images and a corner list per pixel), and per feature the
  // feature, its word, a match and its inlier flag.
  constexpr size_t kFeatureBytesPerPixel = 3 * sizeof(float) + 2;
  const size_t pixels = static_cast<size_t>(params.camera.width_px) * params.camera.height_px;
  return pixels * kFeatureBytesPerPixel +
         static_cast<size_t>(params.loop.features) *
             (sizeof(Feature) + sizeof(BowEntry) + sizeof(PointPair) + 1);
}

void PlaceRecognizer::allocate(const Params& params) {
  FeatureOptions opt;
  opt.max_features = params.loop.features;
  extractor_.allocate(params.camera.width_px, params.camera.height_px, opt);
  features_.reserve_once(opt.max_features);
  bow_.reserve_once(opt.max_features);
  pairs_.reset(new PointPair[static_cast<size_t>(opt.max_features)]);
  inlier_.reset(new uint8_t[static_cast<size_t>(opt.max_features)]);
}

void PlaceRecognizer::describe(const ImageF& gray, const ImageF& inverse_depth,
                               const PinholeIntrinsics& k, const Vocabulary& vocabulary) {
  extractor_.extract(gray, inverse_depth, k, &features_);
  vocabulary.transform(features_, &bow_);
}

RigidRansacResult PlaceRecognizer::verify(const FixedVector<Feature>& query,
                                          const PlaceRecord& place,
                                          const VerificationLimits& limits) {
  const int n = match_features(query, place.features, pairs_.get(), features_.capacity());
  RigidRansacOptions opt;
  opt.inverse_depth_sigma = limits.inverse_depth_sigma;
  opt.seed = place.keyframe_id + 1;
  RigidRansacResult r = rigid_ransac(pairs_.get(), n, opt, inlier_.get());
  if (r.inliers < limits.min_inliers) r.inliers = 0;
  return r;
}

int PlaceRecognizer::add_appearance_candidates(PlaceStore& store, PlaceDatabase::Filter allowed,
                                               const void* context, int max,
                                               const VerificationLimits& limits,
                                               PlaceCandidate* out, int n) {
  constexpr int kMaxMatches = 8;
  constexpr float kMinRelativeScore = 0.5f;
  PlaceMatch matches[kMaxMatches];
  const int found =
      store.database().query(bow_, allowed, context, matches, std::min(max, kMaxMatches));
  for (int i = 0; i < found && matches[i].score >= kMinRelativeScore * matches[0].score; ++i) {
    bool chosen = false;
    for (int k = 0; k < n; ++k) chosen |= out[k].slot == matches[i].slot;
    if (chosen) continue;
    PlaceCandidate& c = out[n++];
    c = PlaceCandidate();
    c.slot = matches[i].slot;
    const RigidRansacResult fit = verify(store.at_slot(c.slot), limits);
    if (fit.inliers > 0) c.add_guess(fit.T_b_a);
  }
  return n;
}

}  // namespace rgbdtam

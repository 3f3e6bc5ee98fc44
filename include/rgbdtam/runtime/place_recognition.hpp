#pragma once
// The light keyframe store that loop closure and relocalisation share, and the recogniser
// both use to describe a view and find a first guess of a match.
//
// Every keyframe leaves a light record (pose, features with 3-D points, bag-of-words vector, and
// its coarse view for direct alignment) that outlives its dense slot in the tracker's pool, so
// the map remembers far more places than the pool holds. Records live in slots of fixed capacity; a
// handle (slot, generation) goes stale when its slot is reused. Policy when full: the oldest record
// is evicted (counted), as a ring: a robot that runs for hours keeps the places of its last
// `loop.places` keyframes (less those kept, keep_oldest). Threads: the loop module writes, the
// tracker reads (relocalisation); both under mutex().

#include <atomic>
#include <mutex>

#include "rgbdtam/core/place_database.hpp"
#include "rgbdtam/core/rigid_alignment.hpp"
#include "rgbdtam/port/messages.hpp"
#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {

struct PlaceRecord {
  uint32_t keyframe_id = 0;
  uint32_t generation = 0;
  int64_t timestamp_ns = 0;
  SE3 T_w_k;
  FixedVector<Feature> features;
  BowVector bow;
  View view;
  // Its image repeats along a surface: a match with it does not say where the camera is along
  // that surface, so it neither relocalises nor closes a loop (not kept in map files).
  bool repeats = false;
};

struct PlaceHandle {
  int slot = -1;
  uint32_t generation = 0;
};

class PlaceStore {
 public:
  // camera: the full-resolution camera, whose view level every place keeps.
  void allocate(int capacity, int features_per_place, int words, const PinholeIntrinsics& camera);
  std::mutex& mutex() { return mutex_; }

  // Under the lock. The record the next keyframe goes to, the oldest evicted when full; fill
  // it, then commit() indexes it.
  PlaceRecord* begin_insert();
  void commit();
  int size() const { return size_; }
  int capacity() const { return capacity_; }
  // The oldest `count` records are never forgotten (a map loaded to localise in); the rest of
  // the store is the ring. Under the lock, with fewer than capacity() records.
  void keep_oldest(int count);
  int kept() const { return kept_; }
  // Records forgotten to make room; read from any thread (the firmware reports the first).
  uint32_t evicted() const { return evicted_.load(std::memory_order_relaxed); }
  // Oldest first.
  PlaceRecord& in_order(int i) { return records_[slot_of(i)]; }
  const PlaceRecord& in_order(int i) const { return records_[slot_of(i)]; }
  // The order index of a keyframe's record, or -1 when it is not (or no longer) remembered.
  int order_of(uint32_t keyframe_id) const;
  const PlaceRecord& at_slot(int slot) const { return records_[slot]; }
  // Under the lock: the place at slot looks like another the map knows to be elsewhere.
  void mark_repeats(int slot) { records_[slot].repeats = true; }
  PlaceHandle handle(int order) const;
  const PlaceRecord* get(const PlaceHandle& h) const;
  // Lookups refused because the handle's record had been forgotten (any thread).
  uint32_t stale_lookups() const { return stale_lookups_.load(std::memory_order_relaxed); }
  PlaceDatabase& database() { return database_; }

  // Bytes that allocate() takes, for the memory budget.
  static size_t bytes_needed(int capacity, int features_per_place, int words,
                             const PinholeIntrinsics& camera);

 private:
  // Kept records are in the first slots; the ring's oldest is at first_.
  int slot_of(int order) const {
    return order < kept_ ? order : kept_ + (first_ - kept_ + order - kept_) % (capacity_ - kept_);
  }

  std::mutex mutex_;
  std::unique_ptr<PlaceRecord[]> records_;
  PlaceDatabase database_;
  int capacity_ = 0, size_ = 0, first_ = 0, kept_ = 0;
  std::atomic<uint32_t> evicted_{0};
  mutable std::atomic<uint32_t> stale_lookups_{0};
};

// What a feature match must show to give a first guess of a place's pose (direct alignment of
// the views decides whether it is the place).
struct VerificationLimits {
  int min_inliers = 12;
  double inverse_depth_sigma = 0.01;  // the sensor's, for the inlier threshold
  static VerificationLimits of(const Params& p) {
    return {p.loop.min_inliers, p.sensor.inverse_depth_sigma()};
  }
};

// A remembered place to align a view with, and first guesses of the view's pose in it.
struct PlaceCandidate {
  static constexpr int kMaxGuesses = 3;
  int slot = -1;
  EdgeKind kind = EdgeKind::kRevisit;
  SE3 guesses[kMaxGuesses];  // T_place_view
  int guess_count = 0;
  void add_guess(const SE3& T_place_view) {
    if (guess_count < kMaxGuesses) guesses[guess_count++] = T_place_view;
  }
};

// Describes one view (features, bag of words) and finds it among remembered places.
class PlaceRecognizer {
 public:
  void allocate(const Params& params);
  static size_t bytes_needed(const Params& params);
  void describe(const ImageF& gray, const ImageF& inverse_depth, const PinholeIntrinsics& k,
                const Vocabulary& vocabulary);
  const FixedVector<Feature>& features() const { return features_; }
  const BowVector& bow() const { return bow_; }
  // Descriptor matches lifted to 3-D, RANSAC with Horn's closed form: T_b_a is this view in the
  // place's keyframe. inliers = 0 when it does not fit.
  RigidRansacResult verify(const PlaceRecord& place, const VerificationLimits& limits) {
    return verify(features_, place, limits);
  }
  // The same for other features than the described view's (at most loop.features).
  RigidRansacResult verify(const FixedVector<Feature>& query, const PlaceRecord& place,
                           const VerificationLimits& limits);
  // Appends to out[n..) the described view's best places by bag of words among those allowed
  // and not in out yet, at most `max` and each within half the best score, with the features'
  // fit as the first guess where they fit. Returns the new count. Under the store's lock.
  int add_appearance_candidates(PlaceStore& store, PlaceDatabase::Filter allowed,
                                const void* context, int max, const VerificationLimits& limits,
                                PlaceCandidate* out, int n);

 private:
  FeatureExtractor extractor_;
  FixedVector<Feature> features_;
  BowVector bow_;
  std::unique_ptr<PointPair[]> pairs_;
  std::unique_ptr<uint8_t[]> inlier_;
};

}  // namespace rgbdtam

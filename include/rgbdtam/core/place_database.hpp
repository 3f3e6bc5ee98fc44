#pragma once
// An inverted index over places' bag-of-words vectors (DBoW2's database): for every word, the
// places that contain it, so that a query touches only places sharing a word with it. Fixed
// capacity: `places` slots of at most `max_words_per_place` words, sized in allocate(); add,
// remove and query never allocate.

#include <cstdint>
#include <memory>

#include "rgbdtam/core/vocabulary.hpp"

namespace rgbdtam {

struct PlaceMatch {
  int slot = -1;
  float score = 0.f;  // bow_score with the query
};

class PlaceDatabase {
 public:
  void allocate(int places, int words, int max_words_per_place);
  // Replaces what the slot held; words beyond max_words_per_place are left out (the lightest).
  void add(int slot, const BowVector& v);
  void remove(int slot);
  // The `max` best places with allowed(context, slot), best first; returns how many. Uses the
  // database's own scratch: one query at a time.
  using Filter = bool (*)(const void* context, int slot);
  int query(const BowVector& v, Filter allowed, const void* context, PlaceMatch* out, int max);
  int places() const { return places_; }

 private:
  struct Entry {
    uint32_t word = 0;
    float weight = 0.f;
    int32_t prev = -1, next = -1;  // neighbours in the word's list, entry indices
  };
  int places_ = 0, words_ = 0, per_place_ = 0;
  std::unique_ptr<int32_t[]> head_;     // per word: first entry, -1 for none
  std::unique_ptr<Entry[]> entries_;    // slot * per_place_ + i
  std::unique_ptr<int32_t[]> count_;    // entries per slot
  std::unique_ptr<float[]> score_;      // per slot, zero between queries
  std::unique_ptr<int32_t[]> touched_;  // slots with a score in this query
};

}  // namespace rgbdtam

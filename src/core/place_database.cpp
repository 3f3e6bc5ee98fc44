#include "rgbdtam/core/place_database.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdtam {

void PlaceDatabase::allocate(int places, int words, int max_words_per_place) {
  RGBDTAM_ASSERT(places > 0 && words > 0 && max_words_per_place > 0, "empty place database");
  places_ = places;
  words_ = words;
  per_place_ = max_words_per_place;
  head_.reset(new int32_t[static_cast<size_t>(words)]);
  std::fill(head_.get(), head_.get() + words, -1);
  entries_.reset(new Entry[static_cast<size_t>(places) * static_cast<size_t>(per_place_)]);
  count_.reset(new int32_t[static_cast<size_t>(places)]());
  score_.reset(new float[static_cast<size_t>(places)]());
  touched_.reset(new int32_t[static_cast<size_t>(places)]);
}

void PlaceDatabase::remove(int slot) {
  RGBDTAM_ASSERT(slot >= 0 && slot < places_, "place slot out of range");
  Entry* block = &entries_[static_cast<size_t>(slot) * per_place_];
  for (int i = 0; i < count_[slot]; ++i) {
    Entry& e = block[i];
    if (e.prev >= 0) {
      entries_[e.prev].next = e.next;
    } else {
      head_[e.word] = e.next;
    }
    if (e.next >= 0) entries_[e.next].prev = e.prev;
  }
  count_[slot] = 0;
}

void PlaceDatabase::add(int slot, const BowVector& v) {
  remove(slot);
  const int32_t first = slot * per_place_;
  int n = 0;
  for (const BowEntry& w : v) {
    if (n == per_place_) break;  // callers size per_place_ to the features: does not happen
    RGBDTAM_ASSERT(w.word < static_cast<uint32_t>(words_), "word beyond the vocabulary");
    Entry& e = entries_[first + n];
    e.word = w.word;
    e.weight = w.weight;
    e.prev = -1;
    e.next = head_[w.word];
    if (e.next >= 0) entries_[e.next].prev = first + n;
    head_[w.word] = first + n;
    ++n;
  }
  count_[slot] = n;
}

int PlaceDatabase::query(const BowVector& v, Filter allowed, const void* context, PlaceMatch* out,
                         int max) {
  int touched = 0;
  for (const BowEntry& q : v) {
    if (q.word >= static_cast<uint32_t>(words_)) continue;
    for (int32_t i = head_[q.word]; i >= 0; i = entries_[i].next) {
      const Entry& e = entries_[i];
      const int slot = i / per_place_;
      if (score_[slot] == 0.f) touched_[touched++] = slot;
      // DBoW2's L1 score, accumulated over the words in common.
      score_[slot] += std::min(q.weight, e.weight);
    }
  }
  int n = 0;
  for (int t = 0; t < touched; ++t) {
    const int slot = touched_[t];
    const float s = score_[slot];
    score_[slot] = 0.f;
    if (allowed != nullptr && !allowed(context, slot)) continue;
    // Insertion into the short best-first list.
    if (n == max && (max == 0 || s <= out[n - 1].score)) continue;
    int j = n < max ? n++ : n - 1;
    while (j > 0 && (out[j - 1].score < s || (out[j - 1].score == s && out[j - 1].slot > slot))) {
      out[j] = out[j - 1];
      --j;
    }
    out[j] = {slot, s};
  }
  return n;
}

}  // namespace rgbdtam

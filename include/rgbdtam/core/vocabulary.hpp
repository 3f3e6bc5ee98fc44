#pragma once
// A bag-of-words vocabulary of binary descriptors (Galvez-Lopez and Tardos's DBoW2 scheme): a
// tree of k-medians clusters, `branching` children per node and `depth` levels, whose leaves are
// the words, each weighted by its inverse document frequency. Trained offline (train() may
// allocate); at run time parse() fills memory sized once from the file's header and transform()
// never allocates.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "rgbdtam/core/features.hpp"
#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

struct BowEntry {
  uint32_t word;
  float weight;
};
// Sorted by word, weights summing to 1 (tf-idf, L1-normalised).
using BowVector = FixedVector<BowEntry>;

class Vocabulary {
 public:
  struct Node {
    Descriptor centre;
    int32_t first_child = -1;  // children are contiguous; -1 for a word
    uint16_t children = 0;
    int32_t word = -1;
    float idf = 0.f;
  };

  // images[i] holds the descriptors of one training image. Deterministic for equal input.
  static Vocabulary train(const std::vector<std::vector<Descriptor>>& images, int branching,
                          int depth);
  // The file format: "RGBDVOC1", then little-endian u32 branching, depth, nodes, words, then
  // each node (32-byte centre, i32 first child, u16 children, u16 zero, i32 word, f32 idf),
  // then a u32 FNV-1a checksum of everything before it.
  size_t serialized_size() const;
  void serialize(uint8_t* out) const;
  // Validates everything (sizes, links, words, weights, checksum) before using any of it.
  static Status parse(const uint8_t* data, size_t size, Vocabulary* out);

  int words() const { return words_; }
  // The file's checksum: what a map file records of the vocabulary its places were described in.
  uint32_t checksum() const { return checksum_; }
  int nodes() const { return nodes_count_; }
  int branching() const { return branching_; }
  int depth() const { return depth_; }
  int word_of(const Descriptor& d) const;
  // out: capacity at least the number of features.
  void transform(const FixedVector<Feature>& features, BowVector* out) const;

 private:
  void index_words();

  std::unique_ptr<Node[]> nodes_;
  std::unique_ptr<float[]> word_idf_;
  int nodes_count_ = 0;
  int words_ = 0;
  int branching_ = 0;
  int depth_ = 0;
  uint32_t checksum_ = 0;
};

// DBoW2's L1 score of two BoW vectors: 1 for the same words in the same proportions, 0 for none
// in common.
double bow_score(const BowVector& a, const BowVector& b);

}  // namespace rgbdtam

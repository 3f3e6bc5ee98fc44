#include "rgbdtam/core/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rgbdtam/core/byte_io.hpp"
#include "rgbdtam/core/xorshift.hpp"

namespace rgbdtam {
namespace {
constexpr char kMagic[8] = {'R', 'G', 'B', 'D', 'V', 'O', 'C', '1'};
constexpr size_t kHeaderBytes = 8 + 4 * 4;
constexpr size_t kNodeBytes = 32 + 4 + 2 + 2 + 4 + 4;
constexpr int kKMediansIterations = 10;

// Bitwise majority of the members: the binary k-medians centre.
Descriptor majority(const std::vector<Descriptor>& all, const std::vector<int>& members) {
  int ones[256] = {};
  for (const int m : members) {
    for (int b = 0; b < 256; ++b)
      ones[b] += static_cast<int>((all[m].bits[b / 64] >> (b % 64)) & 1u);
  }
  Descriptor c;
  for (int b = 0; b < 256; ++b) {
    if (2 * ones[b] > static_cast<int>(members.size())) c.bits[b / 64] |= uint64_t{1} << (b % 64);
  }
  return c;
}

// k-medians of all[members] with k-means++ seeding; empty clusters are dropped.
std::vector<std::vector<int>> cluster(const std::vector<Descriptor>& all,
                                      const std::vector<int>& members, int k, uint32_t* seed,
                                      std::vector<Descriptor>* centres) {
  const int n = static_cast<int>(members.size());
  centres->clear();
  centres->push_back(all[members[xorshift32(seed) % n]]);
  std::vector<double> nearest(n);
  while (static_cast<int>(centres->size()) < k) {
    double total = 0.0;
    for (int i = 0; i < n; ++i) {
      int d = 256;
      for (const Descriptor& c : *centres) d = std::min(d, hamming(all[members[i]], c));
      nearest[i] = static_cast<double>(d) * d;
      total += nearest[i];
    }
    if (total == 0.0) break;  // fewer distinct descriptors than k
    double pick = total * (xorshift32(seed) / 4294967296.0);
    int chosen = n - 1;
    for (int i = 0; i < n; ++i) {
      pick -= nearest[i];
      if (pick < 0.0) {
        chosen = i;
        break;
      }
    }
    centres->push_back(all[members[chosen]]);
  }
  std::vector<int> assignment(n, -1);
  std::vector<std::vector<int>> groups;
  for (int it = 0; it < kKMediansIterations; ++it) {
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      int best = 0, best_d = 257;
      for (int c = 0; c < static_cast<int>(centres->size()); ++c) {
        const int d = hamming(all[members[i]], (*centres)[c]);
        if (d < best_d) best = c, best_d = d;
      }
      changed = changed || assignment[i] != best;
      assignment[i] = best;
    }
    groups.assign(centres->size(), {});
    for (int i = 0; i < n; ++i) groups[assignment[i]].push_back(members[i]);
    if (!changed) break;
    for (size_t c = 0; c < groups.size(); ++c) {
      if (!groups[c].empty()) (*centres)[c] = majority(all, groups[c]);
    }
  }
  std::vector<std::vector<int>> kept;
  std::vector<Descriptor> kept_centres;
  for (size_t c = 0; c < groups.size(); ++c) {
    if (groups[c].empty()) continue;
    kept.push_back(std::move(groups[c]));
    kept_centres.push_back((*centres)[c]);
  }
  *centres = kept_centres;
  return kept;
}
}  // namespace

Vocabulary Vocabulary::train(const std::vector<std::vector<Descriptor>>& images, int branching,
                             int depth) {
  RGBDTAM_ASSERT(branching >= 2 && depth >= 1, "vocabulary needs branching >= 2, depth >= 1");
  std::vector<Descriptor> all;
  for (const auto& image : images) all.insert(all.end(), image.begin(), image.end());
  RGBDTAM_ASSERT(!all.empty(), "no descriptors to train a vocabulary on");
  std::vector<Node> nodes(1);
  struct Pending {
    int node, level;
    std::vector<int> members;
  };
  std::vector<Pending> queue;
  queue.push_back({0, 0, {}});
  for (int i = 0; i < static_cast<int>(all.size()); ++i) queue[0].members.push_back(i);
  uint32_t seed = 0x2545F491u;
  std::vector<Descriptor> centres;
  // Breadth first, so that siblings are contiguous.
  for (size_t q = 0; q < queue.size(); ++q) {
    const int node = queue[q].node, level = queue[q].level;
    std::vector<int> members = std::move(queue[q].members);
    if (level == depth || members.size() <= 1) continue;
    const std::vector<std::vector<int>> groups = cluster(all, members, branching, &seed, &centres);
    if (groups.size() <= 1 && level > 0) continue;
    nodes[node].first_child = static_cast<int32_t>(nodes.size());
    nodes[node].children = static_cast<uint16_t>(groups.size());
    for (size_t c = 0; c < groups.size(); ++c) {
      Node child;
      child.centre = centres[c];
      nodes.push_back(child);
      queue.push_back({static_cast<int>(nodes.size()) - 1, level + 1, groups[c]});
    }
  }
  Vocabulary v;
  v.branching_ = branching;
  v.depth_ = depth;
  v.nodes_count_ = static_cast<int>(nodes.size());
  v.nodes_.reset(new Node[nodes.size()]);
  for (size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i].children == 0) nodes[i].word = v.words_++;
    v.nodes_[i] = nodes[i];
  }
  // idf = log(N / n_w): a word seen in every training image tells nothing.
  std::vector<int> images_with(v.words_, 0), last_image(v.words_, -1);
  for (int i = 0; i < static_cast<int>(images.size()); ++i) {
    for (const Descriptor& d : images[i]) {
      const int w = v.word_of(d);
      if (last_image[w] != i) ++images_with[w], last_image[w] = i;
    }
  }
  const double n = static_cast<double>(images.size());
  for (int i = 0; i < v.nodes_count_; ++i) {
    Node& node = v.nodes_[i];
    if (node.word >= 0) {
      node.idf = static_cast<float>(std::log(n / std::max(1, images_with[node.word])));
    }
  }
  v.index_words();
  std::vector<uint8_t> file(v.serialized_size());
  v.serialize(file.data());
  std::memcpy(&v.checksum_, file.data() + file.size() - 4, 4);
  return v;
}

void Vocabulary::index_words() {
  word_idf_.reset(new float[static_cast<size_t>(words_)]());
  for (int i = 0; i < nodes_count_; ++i) {
    if (nodes_[i].word >= 0) word_idf_[nodes_[i].word] = nodes_[i].idf;
  }
}

int Vocabulary::word_of(const Descriptor& d) const {
  int node = 0;
  while (nodes_[node].children > 0) {
    const Node& parent = nodes_[node];
    int best = parent.first_child, best_d = 257;
    for (int c = parent.first_child; c < parent.first_child + parent.children; ++c) {
      const int dist = hamming(d, nodes_[c].centre);
      if (dist < best_d) best = c, best_d = dist;
    }
    node = best;
  }
  return nodes_[node].word;
}

void Vocabulary::transform(const FixedVector<Feature>& features, BowVector* out) const {
  RGBDTAM_ASSERT(out->capacity() >= features.size(), "BoW vector smaller than the features");
  out->clear();
  for (const Feature& f : features) {
    (void)out->push_back({static_cast<uint32_t>(word_of(f.descriptor)), 1.f});
  }
  std::sort(out->begin(), out->end(),
            [](const BowEntry& a, const BowEntry& b) { return a.word < b.word; });
  // Merge repeated words into tf counts, weight by idf, normalise to a sum of 1.
  int n = 0;
  for (int i = 0; i < out->size(); ++i) {
    if (n > 0 && (*out)[n - 1].word == (*out)[i].word) {
      (*out)[n - 1].weight += 1.f;
    } else {
      (*out)[n++] = (*out)[i];
    }
  }
  double total = 0.0;
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    const float w = (*out)[i].weight * word_idf_[(*out)[i].word];
    if (w <= 0.f) continue;
    (*out)[kept++] = {(*out)[i].word, w};
    total += w;
  }
  out->truncate(kept);
  if (total > 0.0) {
    for (BowEntry& e : *out) e.weight = static_cast<float>(e.weight / total);
  }
}

size_t Vocabulary::serialized_size() const {
  return kHeaderBytes + kNodeBytes * static_cast<size_t>(nodes_count_) + 4;
}

void Vocabulary::serialize(uint8_t* out) const {
  uint8_t* p = out;
  std::memcpy(p, kMagic, sizeof(kMagic));
  p += sizeof(kMagic);
  put_le<uint32_t>(&p, static_cast<uint32_t>(branching_));
  put_le<uint32_t>(&p, static_cast<uint32_t>(depth_));
  put_le<uint32_t>(&p, static_cast<uint32_t>(nodes_count_));
  put_le<uint32_t>(&p, static_cast<uint32_t>(words_));
  for (int i = 0; i < nodes_count_; ++i) {
    const Node& n = nodes_[i];
    for (const uint64_t b : n.centre.bits) put_le<uint64_t>(&p, b);
    put_le<int32_t>(&p, n.first_child);
    put_le<uint16_t>(&p, n.children);
    put_le<uint16_t>(&p, 0);
    put_le<int32_t>(&p, n.word);
    put_le<float>(&p, n.idf);
  }
  put_le<uint32_t>(&p, fnv1a(out, static_cast<size_t>(p - out)));
}

Status Vocabulary::parse(const uint8_t* data, size_t size, Vocabulary* out) {
  if (size < kHeaderBytes + 4 || std::memcmp(data, kMagic, sizeof(kMagic)) != 0) {
    return Status::error(StatusCode::kCorrupt, "not a vocabulary file (no RGBDVOC1 header)");
  }
  ByteReader p(data + sizeof(kMagic), size - sizeof(kMagic));
  const uint32_t branching = p.get<uint32_t>(), depth = p.get<uint32_t>();
  const uint32_t nodes = p.get<uint32_t>(), words = p.get<uint32_t>();
  if (branching < 2 || branching > 64 || depth < 1 || depth > 8 || nodes < 2 ||
      nodes > 10'000'000 || words < 1 || words >= nodes) {
    return Status::error(StatusCode::kCorrupt,
                         "vocabulary header out of range (branching %u, depth %u, nodes %u, "
                         "words %u)",
                         branching, depth, nodes, words);
  }
  if (size != kHeaderBytes + kNodeBytes * nodes + 4) {
    return Status::error(StatusCode::kCorrupt, "vocabulary of %u nodes should be %zu bytes, is %zu",
                         nodes, kHeaderBytes + kNodeBytes * nodes + 4, size);
  }
  uint32_t checksum;
  std::memcpy(&checksum, data + size - 4, 4);
  if (checksum != fnv1a(data, size - 4)) {
    return Status::error(StatusCode::kCorrupt, "vocabulary checksum mismatch (damaged file)");
  }
  std::unique_ptr<Node[]> parsed(new Node[nodes]);
  uint32_t leaves = 0;
  for (uint32_t i = 0; i < nodes; ++i) {
    Node& n = parsed[i];
    for (uint64_t& b : n.centre.bits) b = p.get<uint64_t>();
    n.first_child = p.get<int32_t>();
    n.children = p.get<uint16_t>();
    (void)p.get<uint16_t>();
    n.word = p.get<int32_t>();
    n.idf = p.get<float>();
    const bool inner = n.children > 0;
    // Children after their parent: the descent always ends.
    const bool links_ok =
        inner ? n.children <= branching && n.first_child > static_cast<int32_t>(i) &&
                    static_cast<uint32_t>(n.first_child) + n.children <= nodes && n.word == -1
              : n.first_child == -1 && n.word >= 0 && static_cast<uint32_t>(n.word) < words &&
                    std::isfinite(n.idf) && n.idf >= 0.f;
    if (!links_ok || (i == 0 && !inner)) {
      return Status::error(StatusCode::kCorrupt, "vocabulary node %u is inconsistent", i);
    }
    leaves += inner ? 0 : 1;
  }
  if (leaves != words) {
    return Status::error(StatusCode::kCorrupt, "vocabulary has %u leaves for %u words", leaves,
                         words);
  }
  out->nodes_ = std::move(parsed);
  out->nodes_count_ = static_cast<int>(nodes);
  out->words_ = static_cast<int>(words);
  out->branching_ = static_cast<int>(branching);
  out->depth_ = static_cast<int>(depth);
  out->checksum_ = checksum;
  out->index_words();
  return Status::ok();
}

double bow_score(const BowVector& a, const BowVector& b) {
  double s = 0.0;
  int i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i].word < b[j].word) {
      ++i;
    } else if (b[j].word < a[i].word) {
      ++j;
    } else {
      s += std::fabs(a[i].weight) + std::fabs(b[j].weight) - std::fabs(a[i].weight - b[j].weight);
      ++i, ++j;
    }
  }
  return 0.5 * s;
}

}  // namespace rgbdtam

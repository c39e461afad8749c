#pragma once
// Binary bag-of-words vocabulary tree over 256-bit ORB descriptors (Galvez-Lopez & Tardos 2012,
// "Bags of binary words for fast place recognition", DBoW2).
//
// Training (hierarchical k-majority). The root holds every training descriptor. A node at level
// l < depth whose members are not all identical is split into at most `branching` children:
//  - with more than `branching` members, by k-medians in Hamming space: centres seeded
//    k-means++-style (first centre uniform, each next one drawn with probability proportional
//    to D(x)^2, D = Hamming distance to the nearest chosen centre; a std::mt19937_64 seeded by
//    VocabularyParams::seed and consumed in node order, so training is deterministic), then
//    alternately: assign every member to its nearest centre (ties -> lowest centre index) and
//    replace each centre by the bitwise majority of its members (bit = 1 when more than half
//    the members have it, ties -> 0), for max_iterations rounds or until no assignment
//    changes; the last step is always an assignment, so members sit with their nearest centre;
//    empty clusters are dropped;
//  - with at most `branching` members, one child per distinct descriptor.
// Nodes are stored breadth first (children of a node are contiguous). Leaves are the words,
// numbered 0 .. numWords() - 1 in that order.
//
// Weights. idf(w) = log(N / n_w), N = number of training images, n_w = number of training images
// with at least one descriptor whose greedy descent (below) ends in w; a word that no training
// image reaches gets log(N). A word present in every image has idf 0 (a stop word).
//
// Transform. Each descriptor descends greedily from the root to the child with the smallest
// Hamming distance (ties -> lowest child index) until it reaches a leaf. For a set of n
// descriptors, tf(w) = count(w) / n and v_w = tf(w) idf(w); entries with v_w = 0 are dropped and
// the vector is L1-normalised (sum v_w = 1; empty when every weight is 0).
//
// Score (DBoW2 L1). s(a, b) = 1 - 0.5 |a - b|_1 for L1-normalised a, b, computed over the common
// words only with |a - b|_1 = 2 - sum_common (|a_i| + |b_i| - |a_i - b_i|); for non-negative
// weights this is sum_common min(a_i, b_i). In [0, 1]: 1 for equal vectors, 0 without a common
// word.
//
// Serialised form (little-endian, no padding): "SVVOC1" (6 bytes), u32 version (= 1), u32
// branching, u32 depth, u32 node count, then per node in breadth-first order: u8 child count
// (0 = leaf), 32-byte centre (the four 64-bit words of OrbDescriptor, each little-endian), and
// for leaves an f32 idf. Node 0 is the root (its centre is unused and stored as zeros).
// k = 10, L = 4 gives at most 11 111 nodes, about 0.41 MB.
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "core/status.hpp"
#include "features/orb_extractor.hpp"

namespace svslam {

struct VocabularyParams {
  int branching = 10;       // k, children per node, 2..255
  int depth = 4;            // L, levels below the root, 1..8 (at most k^L words)
  int max_iterations = 10;  // k-medians rounds per node, 1..1000
  std::uint64_t seed = 7;   // seeds the k-means++ initialisation
  Status validate() const;
};

// Sparse bag-of-words vector: (word id, weight), sorted by word id, weights > 0, sum = 1.
using BowVector = std::vector<std::pair<std::uint32_t, float>>;

// Bitwise majority of `members` (bit = 1 when set in more than half of them; ties -> 0).
// An empty span gives all zeros.
OrbDescriptor bitwiseMajority(std::span<const OrbDescriptor> members);

class BinaryVocabulary {
 public:
  static constexpr std::uint32_t kFormatVersion = 1;

  // Trains on the descriptors of `images` (one vector per image). invalidArgument for bad
  // params, no image, or fewer descriptors in total than `branching`.
  static Result<BinaryVocabulary> train(const std::vector<std::vector<OrbDescriptor>>& images,
                                        const VocabularyParams& params);

  // The bag-of-words vector of `desc` (see the header comment); `out` is overwritten and its
  // capacity reused. With word_ids, word_ids[i] is the word of desc[i].
  void transform(const std::vector<OrbDescriptor>& desc, BowVector& out) const;
  void transform(const std::vector<OrbDescriptor>& desc, BowVector& out,
                 std::vector<std::uint32_t>& word_ids) const;

  // Word reached by one descriptor's greedy descent.
  std::uint32_t wordOf(const OrbDescriptor& d) const;

  // DBoW2 L1 score of two L1-normalised vectors, in [0, 1]; symmetric.
  static double score(const BowVector& a, const BowVector& b);

  int numWords() const { return static_cast<int>(word_node_.size()); }
  int numNodes() const { return static_cast<int>(centre_.size()); }
  int branching() const { return branching_; }
  int depth() const { return depth_; }
  float idf(std::uint32_t word) const { return idf_[word]; }  // word < numWords()

  std::vector<std::uint8_t> serialize() const;
  // corruptData (with the reason) for anything that is not a well-formed serialised vocabulary:
  // wrong magic or version, truncated or trailing bytes, counts out of range or inconsistent
  // with the size, a tree deeper than `depth` or with an internal leaf count mismatch, an idf
  // that is not finite and >= 0. Never reads outside [data, data + n).
  static Result<BinaryVocabulary> deserialize(const std::uint8_t* data, std::size_t n);

 private:
  BinaryVocabulary() = default;
  void finishTree();  // derives first_child_ and word numbering from num_children_

  int branching_ = 0, depth_ = 0;
  std::vector<OrbDescriptor> centre_;       // per node
  std::vector<std::uint8_t> num_children_;  // per node, 0 = leaf
  std::vector<std::uint32_t> first_child_;  // per node (breadth-first, children contiguous)
  std::vector<std::int32_t> word_of_node_;  // per node, -1 for internal nodes
  std::vector<std::uint32_t> word_node_;    // per word, its node
  std::vector<float> idf_;                  // per word
};

}  // namespace svslam

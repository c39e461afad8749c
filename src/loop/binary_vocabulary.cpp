#include "loop/binary_vocabulary.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <random>
#include <string>

namespace svslam {
namespace {

// Adds the bits of `d` to the 256 per-bit counters.
void countBits(const OrbDescriptor& d, std::uint32_t* counts) {
  for (std::size_t w = 0; w < 4; ++w) {
    std::uint64_t bits = d.words[w];
    while (bits) {
      const int b = std::countr_zero(bits);
      ++counts[w * 64 + static_cast<std::size_t>(b)];
      bits &= bits - 1;
    }
  }
}

OrbDescriptor majorityFromCounts(const std::uint32_t* counts, std::size_t n) {
  OrbDescriptor c;
  for (std::size_t j = 0; j < 256; ++j)
    if (2 * static_cast<std::size_t>(counts[j]) > n)
      c.words[j / 64] |= std::uint64_t{1} << (j % 64);
  return c;
}

bool lessDescriptor(const OrbDescriptor& a, const OrbDescriptor& b) { return a.words < b.words; }

// Hierarchical k-majority clustering; nodes appended breadth first.
class Trainer {
 public:
  Trainer(const VocabularyParams& p, std::vector<OrbDescriptor>&& all)
      : p_(p), all_(std::move(all)), rng_(p.seed) {
    perm_.resize(all_.size());
    for (std::size_t i = 0; i < perm_.size(); ++i) perm_[i] = static_cast<std::uint32_t>(i);
  }

  void build(std::vector<OrbDescriptor>& centre, std::vector<std::uint8_t>& num_children) {
    centre.assign(1, OrbDescriptor{});
    num_children.assign(1, 0);
    std::vector<Pending> queue{{0, 0, static_cast<std::uint32_t>(perm_.size()), 0}};
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const Pending nd = queue[q];
      if (nd.level >= p_.depth || allEqual(nd.begin, nd.end)) continue;  // a leaf
      const std::size_t n = nd.end - nd.begin;
      if (n <= static_cast<std::size_t>(p_.branching))
        splitDistinct(nd.begin, nd.end);
      else
        kMajority(nd.begin, nd.end);
      num_children[nd.node] = static_cast<std::uint8_t>(child_begin_.size());
      for (std::size_t c = 0; c < child_begin_.size(); ++c) {
        const auto node = static_cast<std::uint32_t>(centre.size());
        centre.push_back(child_centre_[c]);
        num_children.push_back(0);
        queue.push_back({node, child_begin_[c], child_end_[c], nd.level + 1});
      }
    }
  }

 private:
  struct Pending {
    std::uint32_t node, begin, end;
    int level;
  };

  const OrbDescriptor& member(std::uint32_t i) const { return all_[perm_[i]]; }

  bool allEqual(std::uint32_t b, std::uint32_t e) const {
    for (std::uint32_t i = b + 1; i < e; ++i)
      if (!(member(i) == member(b))) return false;
    return true;
  }

  void splitDistinct(std::uint32_t b, std::uint32_t e) {
    std::sort(perm_.begin() + b, perm_.begin() + e, [&](std::uint32_t x, std::uint32_t y) {
      return lessDescriptor(all_[x], all_[y]) || (all_[x] == all_[y] && x < y);
    });
    child_begin_.clear();
    child_end_.clear();
    child_centre_.clear();
    for (std::uint32_t i = b; i < e; ++i) {
      if (i == b || !(member(i) == member(i - 1))) {
        if (i != b) child_end_.push_back(i);
        child_begin_.push_back(i);
        child_centre_.push_back(member(i));
      }
    }
    child_end_.push_back(e);
  }

  double uniform01() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }

  void seedCentres(std::uint32_t b, std::uint32_t e) {
    const std::size_t n = e - b;
    centres_.clear();
    centres_.push_back(member(b + static_cast<std::uint32_t>(rng_() % n)));
    min_dist_.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      min_dist_[i] = hammingDistance(member(b + static_cast<std::uint32_t>(i)), centres_[0]);
    while (centres_.size() < static_cast<std::size_t>(p_.branching)) {
      double sum = 0;
      for (int d : min_dist_) sum += static_cast<double>(d) * d;
      if (sum <= 0) break;  // every member coincides with a centre
      const double r = uniform01() * sum;
      double acc = 0;
      std::size_t pick = n;
      for (std::size_t i = 0; i < n; ++i) {
        acc += static_cast<double>(min_dist_[i]) * min_dist_[i];
        if (min_dist_[i] > 0 && acc > r) {
          pick = i;
          break;
        }
      }
      if (pick == n)  // rounding at the very end: the last member off the centres
        for (std::size_t i = n; i-- > 0;)
          if (min_dist_[i] > 0) {
            pick = i;
            break;
          }
      centres_.push_back(member(b + static_cast<std::uint32_t>(pick)));
      for (std::size_t i = 0; i < n; ++i)
        min_dist_[i] =
            std::min(min_dist_[i],
                     hammingDistance(member(b + static_cast<std::uint32_t>(i)), centres_.back()));
    }
  }

  bool assign(std::uint32_t b, std::uint32_t e) {
    bool changed = false;
    for (std::uint32_t i = b; i < e; ++i) {
      int best = 0, best_d = hammingDistance(member(i), centres_[0]);
      for (std::size_t c = 1; c < centres_.size(); ++c) {
        const int d = hammingDistance(member(i), centres_[c]);
        if (d < best_d) best_d = d, best = static_cast<int>(c);
      }
      if (assignment_[i - b] != best) changed = true;
      assignment_[i - b] = best;
    }
    return changed;
  }

  void kMajority(std::uint32_t b, std::uint32_t e) {
    const std::size_t n = e - b;
    seedCentres(b, e);
    const std::size_t k = centres_.size();
    assignment_.assign(n, -1);
    for (int it = 0;; ++it) {
      if (!assign(b, e) || it == p_.max_iterations) break;
      counts_.assign(k * 256, 0);
      sizes_.assign(k, 0);
      for (std::size_t i = 0; i < n; ++i) {
        const auto c = static_cast<std::size_t>(assignment_[i]);
        ++sizes_[c];
        countBits(member(b + static_cast<std::uint32_t>(i)), &counts_[c * 256]);
      }
      for (std::size_t c = 0; c < k; ++c)
        if (sizes_[c] > 0) centres_[c] = majorityFromCounts(&counts_[c * 256], sizes_[c]);
    }
    // Stable partition of the range by cluster; empty clusters are dropped.
    sizes_.assign(k, 0);
    for (int a : assignment_) ++sizes_[static_cast<std::size_t>(a)];
    child_begin_.clear();
    child_end_.clear();
    child_centre_.clear();
    offset_.assign(k, 0);
    std::uint32_t pos = b;
    for (std::size_t c = 0; c < k; ++c) {
      offset_[c] = pos;
      if (sizes_[c] == 0) continue;
      child_begin_.push_back(pos);
      pos += static_cast<std::uint32_t>(sizes_[c]);
      child_end_.push_back(pos);
      child_centre_.push_back(centres_[c]);
    }
    tmp_.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      tmp_[offset_[static_cast<std::size_t>(assignment_[i])]++ - b] = perm_[b + i];
    std::copy(tmp_.begin(), tmp_.end(), perm_.begin() + b);
  }

  VocabularyParams p_;
  std::vector<OrbDescriptor> all_;
  std::vector<std::uint32_t> perm_;  // node members are ranges of this permutation of all_
  std::mt19937_64 rng_;
  std::vector<OrbDescriptor> centres_, child_centre_;
  std::vector<int> min_dist_, assignment_;
  std::vector<std::uint32_t> counts_, child_begin_, child_end_, offset_, tmp_;
  std::vector<std::size_t> sizes_;
};

}  // namespace

Status VocabularyParams::validate() const {
  if (branching < 2 || branching > 255)
    return Status::invalidArgument("branching must be in 2..255");
  if (depth < 1 || depth > 8) return Status::invalidArgument("depth must be in 1..8");
  if (max_iterations < 1 || max_iterations > 1000)
    return Status::invalidArgument("max_iterations must be in 1..1000");
  return Status::ok();
}

OrbDescriptor bitwiseMajority(std::span<const OrbDescriptor> members) {
  std::uint32_t counts[256] = {};
  for (const OrbDescriptor& d : members) countBits(d, counts);
  return majorityFromCounts(counts, members.size());
}

Result<BinaryVocabulary> BinaryVocabulary::train(
    const std::vector<std::vector<OrbDescriptor>>& images, const VocabularyParams& params) {
  if (Status s = params.validate(); !s) return s;
  if (images.empty()) return Status::invalidArgument("vocabulary training: no image");
  std::vector<OrbDescriptor> all;
  std::size_t total = 0;
  for (const auto& im : images) total += im.size();
  if (total < static_cast<std::size_t>(params.branching) || total > 0xFFFFFFFFu)
    return Status::invalidArgument(
        "vocabulary training: " + std::to_string(total) +
        " descriptors, need at least branching = " + std::to_string(params.branching));
  all.reserve(total);
  for (const auto& im : images) all.insert(all.end(), im.begin(), im.end());

  BinaryVocabulary voc;
  voc.branching_ = params.branching;
  voc.depth_ = params.depth;
  Trainer(params, std::move(all)).build(voc.centre_, voc.num_children_);
  voc.finishTree();

  // idf from the images' own greedy descents.
  const std::size_t num_words = voc.word_node_.size();
  std::vector<std::uint32_t> images_with(num_words, 0);
  std::vector<std::size_t> last_image(num_words, images.size());
  for (std::size_t i = 0; i < images.size(); ++i)
    for (const OrbDescriptor& d : images[i]) {
      const std::uint32_t w = voc.wordOf(d);
      if (last_image[w] != i) last_image[w] = i, ++images_with[w];
    }
  const double n_images = static_cast<double>(images.size());
  voc.idf_.resize(num_words);
  for (std::size_t w = 0; w < num_words; ++w)
    voc.idf_[w] = static_cast<float>(std::log(n_images / std::max<double>(1.0, images_with[w])));
  return voc;
}

void BinaryVocabulary::finishTree() {
  const std::size_t n = num_children_.size();
  first_child_.resize(n);
  word_of_node_.assign(n, -1);
  word_node_.clear();
  std::size_t next = 1;
  for (std::size_t i = 0; i < n; ++i) {
    first_child_[i] = static_cast<std::uint32_t>(next);
    next += num_children_[i];
    if (num_children_[i] == 0) {
      word_of_node_[i] = static_cast<std::int32_t>(word_node_.size());
      word_node_.push_back(static_cast<std::uint32_t>(i));
    }
  }
}

std::uint32_t BinaryVocabulary::wordOf(const OrbDescriptor& d) const {
  std::uint32_t node = 0;
  while (num_children_[node] > 0) {
    const std::uint32_t first = first_child_[node];
    const std::uint32_t end = first + num_children_[node];
    std::uint32_t best = first;
    int best_d = hammingDistance(d, centre_[first]);
    for (std::uint32_t c = first + 1; c < end; ++c) {
      const int dist = hammingDistance(d, centre_[c]);
      if (dist < best_d) best_d = dist, best = c;
    }
    node = best;
  }
  return static_cast<std::uint32_t>(word_of_node_[node]);
}

void BinaryVocabulary::transform(const std::vector<OrbDescriptor>& desc, BowVector& out) const {
  out.clear();
  for (const OrbDescriptor& d : desc) out.emplace_back(wordOf(d), 1.0f);
  std::sort(out.begin(), out.end());
  std::size_t j = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (j > 0 && out[j - 1].first == out[i].first)
      out[j - 1].second += 1.0f;
    else
      out[j++] = out[i];
  }
  out.resize(j);
  const double inv_n = desc.empty() ? 0.0 : 1.0 / static_cast<double>(desc.size());
  double sum = 0;
  j = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double v = out[i].second * inv_n * idf_[out[i].first];
    if (v > 0) {
      out[j++] = {out[i].first, static_cast<float>(v)};
      sum += v;
    }
  }
  out.resize(j);
  for (auto& e : out) e.second = static_cast<float>(e.second / sum);
}

void BinaryVocabulary::transform(const std::vector<OrbDescriptor>& desc, BowVector& out,
                                 std::vector<std::uint32_t>& word_ids) const {
  word_ids.resize(desc.size());
  for (std::size_t i = 0; i < desc.size(); ++i) word_ids[i] = wordOf(desc[i]);
  transform(desc, out);
}

double BinaryVocabulary::score(const BowVector& a, const BowVector& b) {
  double s = 0;
  auto i = a.begin(), j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (i->first < j->first) {
      ++i;
    } else if (j->first < i->first) {
      ++j;
    } else {
      const double x = i->second, y = j->second;
      s += std::abs(x) + std::abs(y) - std::abs(x - y);
      ++i, ++j;
    }
  }
  return std::clamp(0.5 * s, 0.0, 1.0);
}

}  // namespace svslam

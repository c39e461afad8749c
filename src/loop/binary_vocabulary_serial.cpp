// BinaryVocabulary's serialised form ("SVVOC1", see binary_vocabulary.hpp): writing and the
// validating reader.
#include <bit>
#include <cmath>
#include <cstring>
#include <string>

#include "loop/binary_vocabulary.hpp"

namespace svslam {
namespace {

constexpr char kMagic[6] = {'S', 'V', 'V', 'O', 'C', '1'};
constexpr std::size_t kHeaderBytes = 6 + 4 * 4;
constexpr std::size_t kNodeBytes = 1 + 32;  // child count + centre (leaves add 4 for the idf)

void putU32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void putU64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
std::uint32_t getU32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(p[i]) << (8 * i);
  return v;
}
std::uint64_t getU64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

}  // namespace

std::vector<std::uint8_t> BinaryVocabulary::serialize() const {
  std::vector<std::uint8_t> out;
  out.reserve(kHeaderBytes + centre_.size() * kNodeBytes + idf_.size() * 4);
  for (char c : kMagic) out.push_back(static_cast<std::uint8_t>(c));
  putU32(out, kFormatVersion);
  putU32(out, static_cast<std::uint32_t>(branching_));
  putU32(out, static_cast<std::uint32_t>(depth_));
  putU32(out, static_cast<std::uint32_t>(centre_.size()));
  for (std::size_t i = 0; i < centre_.size(); ++i) {
    out.push_back(num_children_[i]);
    for (std::uint64_t w : centre_[i].words) putU64(out, w);
    if (num_children_[i] == 0)
      putU32(out, std::bit_cast<std::uint32_t>(idf_[static_cast<std::size_t>(word_of_node_[i])]));
  }
  return out;
}

Result<BinaryVocabulary> BinaryVocabulary::deserialize(const std::uint8_t* data, std::size_t n) {
  auto bad = [](const std::string& why) { return Status::corruptData("vocabulary: " + why); };
  if (data == nullptr || n < kHeaderBytes)
    return bad("truncated header (" + std::to_string(n) + " bytes)");
  if (std::memcmp(data, kMagic, 6) != 0) return bad("wrong magic (not an SVVOC1 vocabulary)");
  const std::uint32_t version = getU32(data + 6), branching = getU32(data + 10),
                      depth = getU32(data + 14), nodes = getU32(data + 18);
  if (version != kFormatVersion) return bad("unsupported version " + std::to_string(version));
  if (branching < 2 || branching > 255) return bad("branching " + std::to_string(branching));
  if (depth < 1 || depth > 8) return bad("depth " + std::to_string(depth));
  if (nodes < 1 || nodes > (n - kHeaderBytes) / kNodeBytes)
    return bad("node count " + std::to_string(nodes) + " inconsistent with " + std::to_string(n) +
               " bytes");
  BinaryVocabulary voc;
  voc.branching_ = static_cast<int>(branching);
  voc.depth_ = static_cast<int>(depth);
  voc.centre_.resize(nodes);
  voc.num_children_.resize(nodes);
  std::size_t pos = kHeaderBytes;
  for (std::size_t i = 0; i < nodes; ++i) {
    if (n - pos < kNodeBytes) return bad("truncated at node " + std::to_string(i));
    const std::uint8_t nc = data[pos];
    if (nc > branching) return bad("node " + std::to_string(i) + " has too many children");
    voc.num_children_[i] = nc;
    for (std::size_t w = 0; w < 4; ++w) voc.centre_[i].words[w] = getU64(data + pos + 1 + 8 * w);
    pos += kNodeBytes;
    if (nc == 0) {
      if (n - pos < 4) return bad("truncated at the idf of node " + std::to_string(i));
      const float idf = std::bit_cast<float>(getU32(data + pos));
      if (!std::isfinite(idf) || idf < 0)
        return bad("idf of node " + std::to_string(i) + " is not finite and >= 0");
      voc.idf_.push_back(idf);
      pos += 4;
    }
  }
  if (pos != n) return bad(std::to_string(n - pos) + " trailing bytes");
  // Breadth-first child counts must describe one tree rooted at node 0, no deeper than depth.
  std::size_t sum = 1;
  for (std::uint8_t nc : voc.num_children_) sum += nc;
  if (sum != nodes) return bad("child counts do not add up to the node count");
  voc.finishTree();
  std::vector<std::uint8_t> level(nodes, 0);
  for (std::size_t i = 0; i < nodes; ++i) {
    if (voc.num_children_[i] == 0) continue;
    if (voc.first_child_[i] <= i) return bad("node " + std::to_string(i) + " is its own ancestor");
    if (level[i] + 1u > depth) return bad("tree deeper than depth " + std::to_string(depth));
    for (std::uint32_t c = 0; c < voc.num_children_[i]; ++c)
      level[voc.first_child_[i] + c] = static_cast<std::uint8_t>(level[i] + 1);
  }
  return voc;
}

}  // namespace svslam

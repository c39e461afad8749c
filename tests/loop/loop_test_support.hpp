#pragma once
// Synthetic ORB descriptors for the loop tests: random prototypes and noisy copies.
#include <cstdint>
#include <random>
#include <vector>

#include "features/orb_extractor.hpp"

namespace svslam::loop_test {

inline OrbDescriptor randomDescriptor(std::mt19937_64& rng) {
  OrbDescriptor d;
  for (auto& w : d.words) w = rng();
  return d;
}

// A copy of `d` with each bit flipped with probability `p_flip`.
inline OrbDescriptor noisyCopy(const OrbDescriptor& d, double p_flip, std::mt19937_64& rng) {
  OrbDescriptor c = d;
  std::bernoulli_distribution flip(p_flip);
  for (int j = 0; j < 256; ++j)
    if (flip(rng)) c.words[static_cast<std::size_t>(j / 64)] ^= std::uint64_t{1} << (j % 64);
  return c;
}

inline std::vector<OrbDescriptor> randomDescriptors(int n, std::mt19937_64& rng) {
  std::vector<OrbDescriptor> v(static_cast<std::size_t>(n));
  for (auto& d : v) d = randomDescriptor(rng);
  return v;
}

// A keyframe seen at a place: noisy copies of a random `keep` share of its prototypes.
inline std::vector<OrbDescriptor> keyframeOf(const std::vector<OrbDescriptor>& prototypes,
                                             double keep, double p_flip, std::mt19937_64& rng) {
  std::vector<OrbDescriptor> out;
  std::bernoulli_distribution take(keep);
  for (const auto& p : prototypes)
    if (take(rng)) out.push_back(noisyCopy(p, p_flip, rng));
  return out;
}

}  // namespace svslam::loop_test

#include "slam/retired_landmark_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace svslam {
namespace {

constexpr std::uint64_t kEmpty = std::numeric_limits<std::uint64_t>::max();
constexpr std::int64_t kIndexLimit = std::int64_t{1} << 20;  // 21 bits per axis

std::uint64_t voxelKey(const Eigen::Vector3d& p, double voxel_m) {
  std::uint64_t key = 0;
  for (int k = 0; k < 3; ++k) {
    const double q = std::clamp(std::floor(p[k] / voxel_m), static_cast<double>(-kIndexLimit),
                                static_cast<double>(kIndexLimit - 1));
    const std::uint64_t biased = static_cast<std::uint64_t>(static_cast<std::int64_t>(q) + kIndexLimit);
    key = (key << 21) | biased;  // < 2^63: never kEmpty
  }
  return key;
}

// Better localised first, the smaller id on ties.
bool better(const MapLandmark& a, const MapLandmark& b) {
  const double ta = a.cov.trace(), tb = b.cov.trace();
  if (ta != tb) return ta < tb;
  return a.id < b.id;
}

std::size_t tableSize(std::size_t n) {
  std::size_t c = 16;
  while (c < 2 * n) c *= 2;
  return c;
}

}  // namespace

RetiredLandmarkMap::RetiredLandmarkMap(double voxel_m, int reserve) : voxel_m_(voxel_m) {
  const std::size_t n = static_cast<std::size_t>(std::max(reserve, 0));
  records_.reserve(n);
  keys_.assign(tableSize(n), kEmpty);
  index_.assign(keys_.size(), -1);
}

std::uint64_t RetiredLandmarkMap::hash(std::uint64_t key) {
  // splitmix64 finaliser.
  key ^= key >> 30;
  key *= 0xbf58476d1ce4e5b9ULL;
  key ^= key >> 27;
  key *= 0x94d049bb133111ebULL;
  key ^= key >> 31;
  return key;
}

std::size_t RetiredLandmarkMap::find(std::uint64_t key) const {
  const std::size_t mask = keys_.size() - 1;
  std::size_t s = static_cast<std::size_t>(hash(key)) & mask;
  while (keys_[s] != kEmpty && keys_[s] != key) s = (s + 1) & mask;
  return s;
}

void RetiredLandmarkMap::grow() {
  std::vector<std::uint64_t> old_keys(keys_.size() * 2, kEmpty);
  std::vector<int> old_index(old_keys.size(), -1);
  old_keys.swap(keys_);
  old_index.swap(index_);
  for (std::size_t s = 0; s < old_keys.size(); ++s) {
    if (old_keys[s] == kEmpty) continue;
    const std::size_t t = find(old_keys[s]);
    keys_[t] = old_keys[s];
    index_[t] = old_index[s];
  }
}

bool RetiredLandmarkMap::insert(const MapLandmark& lm) {
  if (!lm.p_world.allFinite() || !lm.cov.allFinite()) {
    ++rejected_;
    return false;
  }
  const std::uint64_t key = voxelKey(lm.p_world, voxel_m_);
  std::size_t s = find(key);
  if (keys_[s] == key) {
    MapLandmark& kept = records_[static_cast<std::size_t>(index_[s])];
    if (!better(lm, kept)) {
      ++discarded_;
      return false;
    }
    kept = lm;
    ++replaced_;
    return true;
  }
  if (2 * (records_.size() + 1) > keys_.size()) {
    grow();
    s = find(key);
  }
  keys_[s] = key;
  index_[s] = static_cast<int>(records_.size());
  records_.push_back(lm);
  return true;
}

}  // namespace svslam

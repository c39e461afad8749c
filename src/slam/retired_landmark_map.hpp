#pragma once
// The retired part of the landmark map: landmarks out of the filter state, kept for the map
// output (landmarks.ply), at most one per cubic voxel of side voxel_m.
//
// Why a voxel bound: a landmark leaves the state when it is out of view; on a vehicle flying
// over the same ground again, the filter initialises new landmarks on the same surface, and a map
// keeping all of them grows with flight time. One per voxel bounds the map by the volume the
// landmarks occupy (the ground seen, its depth scatter), not by the time flown.
// Which one a voxel keeps: the landmark with the smallest sqrt(trace cov) (the best localised),
// the smaller id on ties, so the result does not depend on the order of equal candidates.
// Voxel of p (world frame, metres): (floor(x / v), floor(y / v), floor(z / v)), each index
// clamped to +-2^20 (beyond about +-10^6 voxels the edge voxels merge: 105 km at 0.1 m).
// Storage: records in a vector (slot per kept landmark) and an open-addressing hash table
// (linear probing, capacity a power of two kept at load <= 1/2), both preallocated for
// `reserve` landmarks; beyond that they grow by doubling. A landmark whose position or
// covariance is not finite is not kept (counted in rejected()).
#include <cstdint>
#include <vector>

#include "slam/map_landmark.hpp"

namespace svslam {

class RetiredLandmarkMap {
 public:
  // voxel_m > 0 (finite); reserve >= 0.
  RetiredLandmarkMap(double voxel_m, int reserve);
  // Offers a retired landmark: kept when its voxel is empty or holds a worse one (replaced).
  // Returns whether it was kept.
  bool insert(const MapLandmark& lm);
  int size() const { return static_cast<int>(records_.size()); }
  // Kept landmarks, in no particular order (deterministic for a given sequence of inserts).
  const std::vector<MapLandmark>& landmarks() const { return records_; }
  std::int64_t replaced() const { return replaced_; }  // kept ones displaced by better ones
  std::int64_t discarded() const { return discarded_; }  // offered, worse than their voxel's
  std::int64_t rejected() const { return rejected_; }    // not finite
  double voxelM() const { return voxel_m_; }

 private:
  static std::uint64_t hash(std::uint64_t key);
  void grow();
  // Table slot holding `key`, or the empty slot where it would go.
  std::size_t find(std::uint64_t key) const;

  double voxel_m_;
  std::vector<MapLandmark> records_;
  std::vector<std::uint64_t> keys_;  // per table slot; kEmpty when free
  std::vector<int> index_;           // per table slot: index into records_
  std::int64_t replaced_ = 0, discarded_ = 0, rejected_ = 0;
};

}  // namespace svslam

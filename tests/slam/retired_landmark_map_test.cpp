// RetiredLandmarkMap: one landmark per voxel (the best localised, the smaller id on ties), the
// count bounded by the volume whatever the number offered, the result independent of the order
// of equal candidates and of the table's growth; against a brute-force reference.
#include "slam/retired_landmark_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <tuple>
#include <vector>

using namespace svslam;

namespace {

MapLandmark landmark(int id, double x, double y, double z, double sigma_m) {
  MapLandmark m;
  m.id = id;
  m.p_world = Eigen::Vector3d(x, y, z);
  m.cov = Eigen::Matrix3d::Identity() * sigma_m * sigma_m;
  return m;
}

std::vector<int> sortedIds(const RetiredLandmarkMap& map) {
  std::vector<int> ids;
  for (const MapLandmark& m : map.landmarks()) ids.push_back(m.id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

}  // namespace

TEST(RetiredLandmarkMap, KeepsTheBestLocalisedOfAVoxel) {
  RetiredLandmarkMap map(0.5, 4);
  EXPECT_TRUE(map.insert(landmark(1, 0.1, 0.1, 0.1, 0.2)));
  EXPECT_FALSE(map.insert(landmark(2, 0.4, 0.2, 0.3, 0.3)));  // same voxel, worse
  EXPECT_TRUE(map.insert(landmark(3, 0.2, 0.49, 0.0, 0.1)));  // same voxel, better
  EXPECT_TRUE(map.insert(landmark(4, 0.6, 0.1, 0.1, 0.9)));   // the next voxel along x
  EXPECT_TRUE(map.insert(landmark(5, -0.1, 0.1, 0.1, 0.9)));  // floor(-0.2) = -1: another voxel
  ASSERT_EQ(map.size(), 3);
  EXPECT_EQ(sortedIds(map), (std::vector<int>{3, 4, 5}));
  EXPECT_EQ(map.replaced(), 1);
  EXPECT_EQ(map.discarded(), 1);
  // Ties on the covariance: the smaller id, whichever comes first.
  EXPECT_FALSE(map.insert(landmark(9, 0.3, 0.3, 0.3, 0.1)));
  EXPECT_TRUE(map.insert(landmark(0, 0.3, 0.3, 0.3, 0.1)));
  EXPECT_EQ(sortedIds(map), (std::vector<int>{0, 4, 5}));
}

TEST(RetiredLandmarkMap, NonFiniteLandmarksAreNotKept) {
  RetiredLandmarkMap map(0.25, 0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(map.insert(landmark(1, nan, 0, 0, 0.1)));
  MapLandmark m = landmark(2, 0, 0, 0, 0.1);
  m.cov(0, 1) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(map.insert(m));
  EXPECT_EQ(map.size(), 0);
  EXPECT_EQ(map.rejected(), 2);
  // Far beyond the index range: clamped into the edge voxel, kept, no overflow.
  EXPECT_TRUE(map.insert(landmark(3, 1e300, -1e300, 0, 0.1)));
  EXPECT_FALSE(map.insert(landmark(4, 1e200, -1e200, 0, 0.2)));
  EXPECT_EQ(map.size(), 1);
}

// Many random landmarks over a small volume, offered again and again (a vehicle flying over the
// same ground): the map holds exactly the brute-force reference's best per voxel, its size never
// above the number of voxels, whatever the reserve (table growth) and the order of the offers.
TEST(RetiredLandmarkMap, BoundedByTheVolumeAndEqualToABruteForceReference) {
  const double voxel = 0.25;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-2.0, 2.0), zpos(0.0, 0.5), sig(0.01, 0.5);
  std::vector<MapLandmark> offered;
  for (int id = 0; id < 20000; ++id)
    offered.push_back(landmark(id, pos(rng), pos(rng), zpos(rng), sig(rng)));

  std::map<std::tuple<long, long, long>, MapLandmark> ref;
  for (const MapLandmark& m : offered) {
    const auto key = std::make_tuple(std::lround(std::floor(m.p_world.x() / voxel)),
                                     std::lround(std::floor(m.p_world.y() / voxel)),
                                     std::lround(std::floor(m.p_world.z() / voxel)));
    auto it = ref.find(key);
    if (it == ref.end()) {
      ref.emplace(key, m);
    } else {
      const double a = m.cov.trace(), b = it->second.cov.trace();
      if (a < b || (a == b && m.id < it->second.id)) it->second = m;
    }
  }
  std::vector<int> ref_ids;
  for (const auto& [key, m] : ref) ref_ids.push_back(m.id);
  std::sort(ref_ids.begin(), ref_ids.end());
  const int voxels = 16 * 16 * 2;  // 4 m x 4 m x 0.5 m
  ASSERT_LE(static_cast<int>(ref_ids.size()), voxels);

  for (const int reserve : {0, 100000}) {
    RetiredLandmarkMap map(voxel, reserve);
    for (const MapLandmark& m : offered) map.insert(m);
    EXPECT_EQ(sortedIds(map), ref_ids) << "reserve " << reserve;
    EXPECT_LE(map.size(), voxels);
    EXPECT_EQ(map.replaced() + map.discarded() + map.size(), 20000);
    std::vector<MapLandmark> reversed(offered.rbegin(), offered.rend());
    RetiredLandmarkMap map_r(voxel, reserve);
    for (const MapLandmark& m : reversed) map_r.insert(m);
    EXPECT_EQ(sortedIds(map_r), ref_ids) << "reverse order, reserve " << reserve;
  }
}

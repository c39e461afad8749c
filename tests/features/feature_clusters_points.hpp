#pragma once
// Seeded 3D point sets shared by the feature-cluster tests.
#include <Eigen/Core>
#include <random>
#include <vector>

namespace svslam::cluster_test {

using Points = std::vector<Eigen::Vector3d>;
using Partition = std::vector<std::vector<int>>;

inline Points uniformPoints(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-3, 3), y(-2, 2), z(3, 9);
  Points p;
  for (int i = 0; i < n; ++i) p.emplace_back(x(rng), y(rng), z(rng));
  return p;
}

// n points in `blobs` Gaussian clumps (sigma 0.15 m) at random centres: uneven, chained data.
inline Points clumpyPoints(int n, int blobs, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-3, 3), y(-2, 2), z(3, 9);
  std::normal_distribution<double> g(0, 0.15);
  Points c, p;
  for (int b = 0; b < blobs; ++b) c.emplace_back(x(rng), y(rng), z(rng));
  for (int i = 0; i < n; ++i)
    p.push_back(c[static_cast<std::size_t>(i % blobs)] + Eigen::Vector3d(g(rng), g(rng), g(rng)));
  return p;
}

// The same distance the library uses: |p_i - p_j| in double, rounded to float.

}  // namespace svslam::cluster_test

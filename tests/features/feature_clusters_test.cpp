// Complete-link clustering against a naive O(n^3) reference, cluster geometry and subsampling.
// ROI projection, bad arguments and the clustering time: feature_clusters_roi_test.cpp.
#include "features/feature_clusters.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "feature_clusters_points.hpp"

namespace svslam {
namespace {

using namespace cluster_test;  // NOLINT: the shared point sets

double pairDist(const Points& p, int i, int j) {
  return static_cast<float>(
      (p[static_cast<std::size_t>(i)] - p[static_cast<std::size_t>(j)]).norm());
}

double completeLink(const Points& p, const std::vector<int>& a, const std::vector<int>& b) {
  double d = 0;
  for (int i : a)
    for (int j : b) d = std::max(d, pairDist(p, i, j));
  return d;
}

// Naive complete link from the definition: recompute every cluster pair's largest member
// distance, merge the closest pair (lowest indices on ties), stop when it exceeds `stop`.
Partition naiveCompleteLink(const Points& p, double stop) {
  Partition cl;
  for (int i = 0; i < static_cast<int>(p.size()); ++i) cl.push_back({i});
  while (cl.size() > 1) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t ba = 0, bb = 0;
    for (std::size_t a = 0; a < cl.size(); ++a)
      for (std::size_t b = a + 1; b < cl.size(); ++b) {
        const double d = completeLink(p, cl[a], cl[b]);
        if (d < best) {
          best = d;
          ba = a;
          bb = b;
        }
      }
    if (best > stop) break;
    cl[ba].insert(cl[ba].end(), cl[bb].begin(), cl[bb].end());
    cl.erase(cl.begin() + static_cast<std::ptrdiff_t>(bb));
  }
  for (auto& c : cl) std::sort(c.begin(), c.end());
  std::sort(cl.begin(), cl.end());
  return cl;
}

Partition partitionOf(const std::vector<Cluster>& out) {
  Partition p;
  for (const auto& c : out) p.push_back(c.members);
  return p;
}

FeatureClusterParams allClusters(double stop) {
  FeatureClusterParams p;
  p.stop_distance_m = stop;
  p.min_cluster_size = 1;
  return p;
}

TEST(FeatureClusters, EqualsNaiveReferenceOnRandomSets) {
  int checked = 0;
  for (const int n : {0, 1, 2, 3, 7, 40, 150, 300})
    for (const double stop : {0.4, 1.0, 2.5})
      for (const bool clumpy : {false, true}) {
        const unsigned seed = static_cast<unsigned>(1000 * n + 10 * stop + clumpy);
        const Points pts = clumpy ? clumpyPoints(n, 12, seed) : uniformPoints(n, seed);
        FeatureClusters fc(allClusters(stop));
        ASSERT_TRUE(fc.initStatus().isOk());
        std::vector<Cluster> out;
        ASSERT_TRUE(fc.process(pts, {}, out).isOk());
        const Partition got = partitionOf(out);
        EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
        EXPECT_EQ(got, naiveCompleteLink(pts, stop)) << "n " << n << " stop " << stop;
        ++checked;
      }
  EXPECT_EQ(checked, 48);
}

TEST(FeatureClusters, SeparatedBlobsGiveTheBlobPartition) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> off(-0.12, 0.12);
  std::discrete_distribution<int> pick({1, 2, 3, 4, 5, 6});  // uneven blob sizes, interleaved
  const std::vector<Eigen::Vector3d> centres = {{-2, -1, 5},  {2, -1, 6},  {0, 1, 4},
                                                {-3, 1.5, 9}, {3, 1.5, 8}, {0, 0, 12}};
  Points pts;
  std::vector<int> blob;
  for (int i = 0; i < 180; ++i) {
    const int b = pick(rng);
    pts.push_back(centres[static_cast<std::size_t>(b)] +
                  Eigen::Vector3d(off(rng), off(rng), off(rng)));
    blob.push_back(b);
  }
  FeatureClusters fc(allClusters(0.5));  // blob diameter < 0.42 m, blobs > 2.5 m apart
  std::vector<Cluster> out;
  ASSERT_TRUE(fc.process(pts, {}, out).isOk());
  Partition truth(6);
  for (int i = 0; i < 180; ++i)
    truth[static_cast<std::size_t>(blob[static_cast<std::size_t>(i)])].push_back(i);
  std::sort(truth.begin(), truth.end());
  EXPECT_EQ(partitionOf(out), truth);
}

TEST(FeatureClusters, StopThresholdSemantics) {
  for (const double stop : {0.3, 0.8, 1.5}) {
    const Points pts = clumpyPoints(400, 25, 11);
    FeatureClusters fc(allClusters(stop));
    std::vector<Cluster> out;
    ASSERT_TRUE(fc.process(pts, {}, out).isOk());
    std::size_t total = 0;
    for (std::size_t a = 0; a < out.size(); ++a) {
      total += out[a].members.size();
      const double diam = completeLink(pts, out[a].members, out[a].members);
      EXPECT_LE(diam, stop);
      EXPECT_DOUBLE_EQ(out[a].diameter_m, diam);
      for (std::size_t b = a + 1; b < out.size(); ++b)
        EXPECT_GT(completeLink(pts, out[a].members, out[b].members), stop);
    }
    EXPECT_EQ(total, pts.size());
  }
}

TEST(FeatureClusters, CentreFarthestRadiusAndQuality) {
  const Points pts = {{0, 0, 5}, {1, 0, 5}, {0, 1, 5}, {2, 2, 5}, {20, 0, 5}};
  const std::vector<float> q = {1, 2, 3, 6, 100};
  FeatureClusterParams p;
  p.stop_distance_m = 3.0;
  p.min_cluster_size = 2;  // drops the lone point at x = 20
  FeatureClusters fc(p);
  std::vector<Cluster> out;
  ASSERT_TRUE(fc.process(pts, q, out).isOk());
  ASSERT_EQ(out.size(), 1u);
  const Cluster& c = out[0];
  EXPECT_EQ(c.members, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_LT((c.centre_m - Eigen::Vector3d(0.75, 0.75, 5)).norm(), 1e-12);
  EXPECT_EQ(c.farthest_m, Eigen::Vector3d(2, 2, 5));
  EXPECT_NEAR(c.radius_m, std::sqrt(2 * 1.25 * 1.25), 1e-12);
  EXPECT_NEAR(c.diameter_m, std::sqrt(8.0), 1e-6);
  EXPECT_FLOAT_EQ(c.mean_quality, 3.0f);
  // Random clusters: centre is the mean, farthest is the member of largest distance.
  const Points r = clumpyPoints(300, 10, 3);
  std::vector<float> rq;
  for (int i = 0; i < 300; ++i) rq.push_back(static_cast<float>(i % 17));
  ASSERT_TRUE(fc.process(r, rq, out).isOk());
  ASSERT_FALSE(out.empty());
  for (const auto& cl : out) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double qs = 0;
    for (int i : cl.members) {
      mean += r[static_cast<std::size_t>(i)];
      qs += rq[static_cast<std::size_t>(i)];
    }
    mean /= static_cast<double>(cl.members.size());
    EXPECT_LT((cl.centre_m - mean).norm(), 1e-12);
    EXPECT_NEAR(cl.mean_quality, qs / static_cast<double>(cl.members.size()), 1e-5);
    EXPECT_GE(cl.members.size(), 2u);
    double far = 0;
    for (int i : cl.members) far = std::max(far, (r[static_cast<std::size_t>(i)] - mean).norm());
    EXPECT_NEAR(cl.radius_m, far, 1e-12);
    EXPECT_NEAR((cl.farthest_m - cl.centre_m).norm(), far, 1e-12);
  }
}

TEST(FeatureClusters, SubsamplesAboveMaxPointsAndReusesOutput) {
  const Points pts = clumpyPoints(130, 8, 5);
  FeatureClusterParams p = allClusters(0.6);
  p.max_points = 50;
  FeatureClusters fc(p);
  std::vector<Cluster> out;
  ASSERT_TRUE(fc.process(uniformPoints(20, 1), {}, out).isOk());  // warm, then reuse `out`
  ASSERT_TRUE(fc.process(pts, {}, out).isOk());
  Points sub;
  std::vector<int> idx;
  for (int k = 0; k < 50; ++k) {
    idx.push_back(k * 130 / 50);
    sub.push_back(pts[static_cast<std::size_t>(idx.back())]);
  }
  Partition expect = naiveCompleteLink(sub, 0.6);
  for (auto& c : expect)
    for (int& i : c) i = idx[static_cast<std::size_t>(i)];
  EXPECT_EQ(partitionOf(out), expect);
  FeatureClusters fresh(p);
  std::vector<Cluster> out2;
  ASSERT_TRUE(fresh.process(pts, {}, out2).isOk());
  EXPECT_EQ(partitionOf(out2), partitionOf(out));
}

}  // namespace
}  // namespace svslam

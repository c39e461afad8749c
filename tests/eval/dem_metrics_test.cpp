// scoreDem on small hand-made rasters whose scores are known.
#include "eval/dem_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <random>
#include <set>
#include <vector>

namespace svslam {
namespace {

// A raster from rows listed top (north) to bottom; NaN = no data. sigma and count are uniform.
map::DemRaster raster(int i0, int j0, int cols, int rows, std::initializer_list<float> h,
                      float sigma_m = 0.1f, float count = 1.0f) {
  map::DemRaster r;
  r.cell_m = 0.5;
  r.i0 = i0;
  r.j0 = j0;
  r.resize(cols, rows);
  auto it = h.begin();
  for (std::size_t k = 0; k < r.height_m.size(); ++k, ++it) {
    r.height_m[k] = *it;
    r.sigma_m[k] = std::isfinite(*it) ? sigma_m : NAN;
    r.count[k] = std::isfinite(*it) ? count : 0.0f;
  }
  return r;
}

TEST(DemMetrics, IdenticalRastersScorePerfectly) {
  const map::DemRaster gt = raster(-2, -1, 2, 2, {1, 2, 3, NAN});
  auto s = scoreDem(gt, gt);
  ASSERT_TRUE(s.isOk()) << s.status().message();
  EXPECT_EQ(s->gt_cells, 3);
  EXPECT_EQ(s->est_cells, 3);
  EXPECT_EQ(s->common_cells, 3);
  EXPECT_DOUBLE_EQ(s->rmse_m, 0);
  EXPECT_DOUBLE_EQ(s->median_abs_m, 0);
  EXPECT_DOUBLE_EQ(s->bias_m, 0);
  EXPECT_DOUBLE_EQ(s->coverage, 1);
  EXPECT_DOUBLE_EQ(s->within_2sigma, 1);
  EXPECT_EQ(s->gt_stereo_cells, 3);
  EXPECT_DOUBLE_EQ(s->coverage_stereo, 1);
}

TEST(DemMetrics, ErrorsOverCommonCells) {
  // gt: 4 cells at 0. est: errors +0.1, -0.3, +0.5 and one cell without data.
  const map::DemRaster gt = raster(0, 0, 4, 1, {0, 0, 0, 0});
  map::DemRaster est = raster(0, 0, 4, 1, {0.1f, -0.3f, 0.5f, NAN}, 0.1f);
  est.sigma_m[1] = 0.2f;  // |e| 0.3 <= 0.4: within; +0.1 within 0.2; +0.5 outside
  auto s = scoreDem(est, gt);
  ASSERT_TRUE(s.isOk());
  EXPECT_EQ(s->gt_cells, 4);
  EXPECT_EQ(s->est_cells, 3);
  EXPECT_EQ(s->common_cells, 3);
  EXPECT_NEAR(s->rmse_m, std::sqrt((0.01 + 0.09 + 0.25) / 3), 1e-7);
  EXPECT_NEAR(s->median_abs_m, 0.3, 1e-7);
  EXPECT_NEAR(s->bias_m, 0.1, 1e-7);
  EXPECT_DOUBLE_EQ(s->coverage, 0.75);
  EXPECT_DOUBLE_EQ(s->within_2sigma, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(s->coverage_stereo, 0.75);
}

TEST(DemMetrics, MedianOfAnEvenCountIsTheMeanOfTheMiddleTwo) {
  const map::DemRaster gt = raster(0, 0, 4, 1, {0, 0, 0, 0});
  const map::DemRaster est = raster(0, 0, 4, 1, {-4, 1, 2, 3});
  auto s = scoreDem(est, gt);
  ASSERT_TRUE(s.isOk());
  EXPECT_DOUBLE_EQ(s->median_abs_m, 2.5);
  EXPECT_DOUBLE_EQ(s->bias_m, 0.5);
}

TEST(DemMetrics, AlignsByMapIndicesAcrossDifferentWindows) {
  // gt: 3 x 2 at i0 = -1, j0 = 10: map cells i in [-1, 1], j in [10, 11]; row 0 is j = 11.
  const map::DemRaster gt = raster(-1, 10, 3, 2, {1, 2, 3, 4, 5, 6});
  // est: 2 x 3 at i0 = 0, j0 = 9: i in [0, 1], j in [9, 11]; row 0 is j = 11.
  //   j = 11: (0, 11) -> gt 2, (1, 11) -> gt 3;  j = 10: (0, 10) -> gt 5, (1, 10) -> gt 6;
  //   j = 9: outside the ground truth.
  const map::DemRaster est = raster(0, 9, 2, 3, {2.5f, 3, 5, 6.5f, 100, 100});
  auto s = scoreDem(est, gt);
  ASSERT_TRUE(s.isOk());
  EXPECT_EQ(s->gt_cells, 6);
  EXPECT_EQ(s->est_cells, 6);
  EXPECT_EQ(s->common_cells, 4);
  EXPECT_NEAR(s->bias_m, 0.25, 1e-12);
  EXPECT_NEAR(s->rmse_m, std::sqrt(0.5 / 4), 1e-12);
  EXPECT_NEAR(s->median_abs_m, 0.25, 1e-12);
  EXPECT_DOUBLE_EQ(s->coverage, 4.0 / 6.0);
}

TEST(DemMetrics, DisjointWindowsHaveNoCommonCells) {
  const map::DemRaster gt = raster(0, 0, 2, 1, {1, 1});
  const map::DemRaster est = raster(5, 5, 2, 1, {1, 1});
  auto s = scoreDem(est, gt);
  ASSERT_TRUE(s.isOk());
  EXPECT_EQ(s->common_cells, 0);
  EXPECT_DOUBLE_EQ(s->coverage, 0);
  EXPECT_DOUBLE_EQ(s->coverage_stereo, 0);
  EXPECT_TRUE(std::isnan(s->rmse_m));
  EXPECT_TRUE(std::isnan(s->median_abs_m));
  EXPECT_TRUE(std::isnan(s->within_2sigma));
}

TEST(DemMetrics, StereoCoverageUsesTheGroundTruthCountBand) {
  // 4 gt cells with heights; count > 0 (seen by both cameras) on the first two only.
  map::DemRaster gt = raster(0, 0, 4, 1, {0, 0, 0, 0});
  gt.count = {3, 1, 0, 0};
  const map::DemRaster est = raster(0, 0, 4, 1, {0, NAN, 0, 0});
  auto s = scoreDem(est, gt);
  ASSERT_TRUE(s.isOk());
  EXPECT_EQ(s->gt_stereo_cells, 2);
  EXPECT_DOUBLE_EQ(s->coverage_stereo, 0.5);
  EXPECT_DOUBLE_EQ(s->coverage, 0.75);
}

TEST(DemMetrics, EmptyGroundTruthGivesNaNShares) {
  const map::DemRaster gt = raster(0, 0, 2, 1, {NAN, NAN});
  auto s = scoreDem(gt, gt);
  ASSERT_TRUE(s.isOk());
  EXPECT_EQ(s->gt_cells, 0);
  EXPECT_TRUE(std::isnan(s->coverage));
  EXPECT_TRUE(std::isnan(s->coverage_stereo));
}

TEST(DemMetrics, BadInputIsAnError) {
  const map::DemRaster gt = raster(0, 0, 2, 1, {1, 1});
  map::DemRaster est = gt;
  est.cell_m = 0.25;
  auto s = scoreDem(est, gt);
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.status().message().find("cell size"), std::string::npos) << s.status().message();
  est = gt;
  est.sigma_m.resize(1);
  EXPECT_FALSE(scoreDem(est, gt).isOk());
  EXPECT_FALSE(scoreDem(gt, est).isOk());
  est = gt;
  est.rows = -1;
  EXPECT_FALSE(scoreDem(est, gt).isOk());
  est = gt;
  est.i0 = 2147483647;
  EXPECT_FALSE(scoreDem(est, gt).isOk());
}

// A tilted road z = 0.05 x + 0.02 y - 1.65 (m) with Gaussian noise of 0.02 m, 0.1 m cells over
// x in [-5, 15], y in [-5, 5]; sigma band 0.03 m. The camera drives along x at z = 0.
class PathStrip : public ::testing::Test {
 protected:
  void SetUp() override {
    dem.cell_m = 0.1;
    dem.i0 = -50;
    dem.j0 = -50;
    dem.resize(200, 100);
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.02);
    for (int r = 0; r < dem.rows; ++r) {
      for (int c = 0; c < dem.cols; ++c) {
        const double x = (dem.i0 + c + 0.5) * 0.1, y = (dem.j0 + dem.rows - 1 - r + 0.5) * 0.1;
        dem.height_m[dem.index(c, r)] = static_cast<float>(0.05 * x + 0.02 * y - 1.65 + noise(rng));
        dem.sigma_m[dem.index(c, r)] = 0.03f;
        dem.count[dem.index(c, r)] = 4;
      }
    }
    for (int k = 0; k <= 100; ++k) path.emplace_back(0.1 * k, 0.0, 0.0);  // x 0..10 m
  }
  // Cells with a height within half_width_m of the path: every cell against every segment.
  std::int64_t bruteForceStrip(double half_width_m) const {
    std::int64_t n = 0;
    for (int r = 0; r < dem.rows; ++r) {
      for (int c = 0; c < dem.cols; ++c) {
        if (!std::isfinite(dem.height_m[dem.index(c, r)])) continue;
        const Eigen::Vector2d p((dem.i0 + c + 0.5) * dem.cell_m,
                                (dem.j0 + dem.rows - 1 - r + 0.5) * dem.cell_m);
        bool in = false;
        for (std::size_t s = 0; s + 1 < path.size() && !in; ++s) {
          const Eigen::Vector2d a = path[s].head<2>(), b = path[s + 1].head<2>();
          if ((b - a).squaredNorm() == 0) continue;  // a point: the neighbours cover it
          const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
          in = (a + t * (b - a) - p).norm() <= half_width_m;
        }
        n += in ? 1 : 0;
      }
    }
    return n;
  }
  map::DemRaster dem;
  std::vector<Eigen::Vector3d> path;
};

TEST_F(PathStrip, PlaneResidualsAreTheNoiseAndTheSlopeIsInTheHeightStd) {
  int c = 0, r = 0;
  ASSERT_TRUE(dem.cellToPixel(50, 30, c, r));  // (5.05, 3.05): 3 m beside the path
  dem.height_m[dem.index(c, r)] = 1000.0f;
  ASSERT_TRUE(dem.cellToPixel(50, 0, c, r));  // on the path, no data: not counted
  dem.height_m[dem.index(c, r)] = NAN;
  auto s = scorePathStrip(dem, path, 1.0);
  ASSERT_TRUE(s.isOk()) << s.status().message();
  EXPECT_EQ(s->strip_cells, bruteForceStrip(1.0));
  EXPECT_GT(s->strip_cells, 2000);
  EXPECT_NEAR(s->path_length_m, 10.0, 1e-9);
  EXPECT_NEAR(s->plane_a, 0.05, 0.002);
  EXPECT_NEAR(s->plane_b, 0.02, 0.005);
  EXPECT_NEAR(s->plane_residual_std_m, 0.02, 0.001);
  EXPECT_NEAR(s->plane_residual_p95_abs_m, 1.96 * 0.02, 0.003);
  // The slope: 0.05 m/m over 12 m of strip gives a std of about 0.05 * 12 / sqrt(12) = 0.17 m.
  EXPECT_GT(s->height_std_m, 0.15);
  EXPECT_LT(s->height_std_m, 0.2);
  EXPECT_FLOAT_EQ(s->median_sigma_m, 0.03f);
  // 1.65 - 0.05 x above the road, x = 0..10 m along the path: 1.40 m on average.
  EXPECT_NEAR(s->camera_height_above_plane_m, 1.40, 0.003);
}

// Things standing on the road (a car roof 1.5 m up on 30 cells, a hole 0.8 m deep on 5) drag the
// plane's RMS; the surface figures leave them out and give back the road's own noise.
TEST_F(PathStrip, SurfaceCellsLeaveOutWhatStandsOnTheRoad) {
  int c = 0, r = 0;
  for (int i = 20; i < 30; ++i)
    for (int j = -1; j <= 1; ++j) {
      ASSERT_TRUE(dem.cellToPixel(i, j, c, r));
      dem.height_m[dem.index(c, r)] += 1.5f;
    }
  for (int i = 60; i < 65; ++i) {
    ASSERT_TRUE(dem.cellToPixel(i, 2, c, r));
    dem.height_m[dem.index(c, r)] -= 0.8f;
  }
  auto s = scorePathStrip(dem, path, 1.0, 0.3);
  ASSERT_TRUE(s.isOk()) << s.status().message();
  EXPECT_GT(s->plane_residual_std_m, 0.1);
  EXPECT_EQ(s->off_surface_cells, 35);
  EXPECT_EQ(s->surface_cells + s->off_surface_cells, s->strip_cells);
  EXPECT_NEAR(s->surface_residual_std_m, 0.02, 0.001);
  auto none = scorePathStrip(dem, path, 1.0, 0.0);  // no band: no surface figures
  ASSERT_TRUE(none.isOk());
  EXPECT_EQ(none->surface_cells, 0);
  EXPECT_TRUE(std::isnan(none->surface_residual_std_m));
  EXPECT_FALSE(scorePathStrip(dem, path, 1.0, NAN).isOk());
}

TEST_F(PathStrip, BoundingBoxesSelectTheSameCellsAsBruteForce) {
  path = {{-2.0, -1.0, 0.0}, {1.0, 2.5, 0.1}, {1.0, 2.5, 0.1}, {4.3, -0.7, 0.0}, {9.0, 4.0, 0.0}};
  for (const double w : {0.05, 0.5, 1.37}) {
    auto s = scorePathStrip(dem, path, w);
    ASSERT_TRUE(s.isOk());
    EXPECT_EQ(s->strip_cells, bruteForceStrip(w)) << w;
  }
}

TEST_F(PathStrip, EmptyStripGivesNulls) {
  for (auto& p : path) p.y() += 50.0;  // beside the raster
  auto s = scorePathStrip(dem, path, 1.0);
  ASSERT_TRUE(s.isOk());
  EXPECT_EQ(s->strip_cells, 0);
  EXPECT_NEAR(s->path_length_m, 10.0, 1e-9);
  EXPECT_TRUE(std::isnan(s->height_std_m));
  EXPECT_TRUE(std::isnan(s->plane_residual_std_m));
  EXPECT_TRUE(std::isnan(s->plane_residual_p95_abs_m));
  EXPECT_TRUE(std::isnan(s->median_sigma_m));
  EXPECT_TRUE(std::isnan(s->camera_height_above_plane_m));
  s = scorePathStrip(dem, {}, 1.0);
  ASSERT_TRUE(s.isOk());
  EXPECT_EQ(s->strip_cells, 0);
}

TEST_F(PathStrip, CellsOnOneLineFixNoPlane) {
  for (auto& p : path) p.y() = 0.05;  // on the centres of row j = 0; the next rows are 0.1 away
  auto s = scorePathStrip(dem, path, 0.03);
  ASSERT_TRUE(s.isOk());
  EXPECT_EQ(s->strip_cells, 100);  // x centres 0.05 .. 9.95 m
  EXPECT_FALSE(std::isnan(s->height_std_m));
  EXPECT_TRUE(std::isnan(s->plane_residual_std_m));
  EXPECT_TRUE(std::isnan(s->camera_height_above_plane_m));
}

TEST_F(PathStrip, BadInputIsAnError) {
  EXPECT_FALSE(scorePathStrip(dem, path, 0.0).isOk());
  EXPECT_FALSE(scorePathStrip(dem, path, NAN).isOk());
  path[3].x() = NAN;
  EXPECT_FALSE(scorePathStrip(dem, path, 1.0).isOk());
  path[3].x() = 0.3;
  dem.count.pop_back();
  EXPECT_FALSE(scorePathStrip(dem, path, 1.0).isOk());
}

TEST(DropPathStart, CutsAtTheHorizontalArcLength) {
  const std::vector<Eigen::Vector3d> path{{0, 0, 0}, {1, 0, 0}, {1, 0, 5}, {3, 0, 2}};
  auto out = dropPathStart(path, 2.0);  // the vertical step has no horizontal length
  ASSERT_EQ(out.size(), 2u);
  EXPECT_TRUE(out[0].isApprox(Eigen::Vector3d(2, 0, 3.5)));
  EXPECT_TRUE(out[1].isApprox(path[3]));
  EXPECT_EQ(dropPathStart(path, 0.0).size(), 4u);
  out = dropPathStart(path, 1.0);  // on a vertex: that vertex once (the last at that length)
  ASSERT_EQ(out.size(), 2u);
  EXPECT_TRUE(out[0].isApprox(path[2]));
  EXPECT_TRUE(dropPathStart(path, 3.5).empty());
}

}  // namespace
}  // namespace svslam

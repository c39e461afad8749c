// scoreDem on small hand-made rasters whose scores are known.
#include "eval/dem_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>

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

}  // namespace
}  // namespace svslam

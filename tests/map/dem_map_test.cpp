// DemMap: tile addressing (negative indices), the 12-byte cell, the fusion of measurements and
// the raster export.
#include "map/dem_map.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace svslam::map {
namespace {

CellMeasurement measurement(double h, double sigma, int count, int lum) {
  CellMeasurement m;
  const double w = 1.0 / (sigma * sigma);
  m.sum_w = w * count;
  m.sum_wh = w * h * count;
  m.sum_var_pose = 0.0;
  m.count = static_cast<std::uint32_t>(count);
  m.sum_luminance = static_cast<std::uint32_t>(lum * count);
  return m;
}

TEST(DemMap, SigmaCodeRoundTripsWithinItsStep) {
  for (double s : {1e-5, 0.003, 0.05, 1.0, 123.0}) {
    EXPECT_NEAR(decodeSigma(encodeSigma(s)) / s, 1.0, 4e-4) << s;
  }
  EXPECT_EQ(encodeSigma(0.0), 0);
  EXPECT_EQ(encodeSigma(NAN), 0);
  EXPECT_EQ(decodeSigma(0), 0.0);
}

TEST(DemMap, TilesAreCreatedOnDemandAtNegativeIndices) {
  DemParams p;
  p.tile_cells = 8;
  p.min_sigma_m = 0.0;
  DemMap map(p);
  ASSERT_TRUE(map.initStatus().isOk());
  EXPECT_EQ(map.tileOf(-1), -1);
  EXPECT_EQ(map.tileOf(-8), -1);
  EXPECT_EQ(map.tileOf(-9), -2);
  EXPECT_EQ(map.tileOf(7), 0);
  EXPECT_EQ(map.tileOf(8), 1);
  EXPECT_EQ(map.cell(-3, 5), nullptr);
  ASSERT_TRUE(map.fuse(-3, 5, measurement(1.5, 0.1, 4, 100), 0, 7));
  EXPECT_EQ(map.numTiles(), 1);
  double h = 0, s = 0;
  ASSERT_TRUE(map.estimate(-3, 5, h, s));
  EXPECT_FLOAT_EQ(h, 1.5f);
  EXPECT_NEAR(s, 0.05, 1e-4);  // 0.1 / sqrt(4)
  EXPECT_FALSE(map.estimate(-2, 5, h, s));
  EXPECT_EQ(map.bytes(), 8u * 8u * 12u);
}

TEST(DemMap, FusionIsTheInverseVarianceMean) {
  DemParams p;
  p.min_sigma_m = 0.0;
  DemMap map(p);
  ASSERT_TRUE(map.fuse(2, 3, measurement(1.0, 0.1, 1, 10), 0, 0));
  ASSERT_TRUE(map.fuse(2, 3, measurement(2.0, 0.2, 1, 30), 1, 0));
  double h = 0, s = 0;
  ASSERT_TRUE(map.estimate(2, 3, h, s));
  // weights 100 and 25: (100 * 1 + 25 * 2) / 125 = 1.2; sigma = 1 / sqrt(125).
  EXPECT_NEAR(h, 1.2, 2e-4);  // the stored sigma is quantised (0.07 % steps)
  EXPECT_NEAR(s, 1.0 / std::sqrt(125.0), 1e-4);
  EXPECT_EQ(map.cell(2, 3)->count, 2);
  EXPECT_EQ(map.cell(2, 3)->luminance_8_8, 20 * 256);
  EXPECT_EQ(map.tiles()[0].first_seq, 0);
  EXPECT_EQ(map.tiles()[0].last_seq, 1);
}

TEST(DemMap, PoseSigmaIsAveragedNotShrunk) {
  DemParams p;
  p.min_sigma_m = 0.0;
  DemMap map(p);
  CellMeasurement m = measurement(0.0, 1e-3, 100, 0);
  m.sum_var_pose = 0.05 * 0.05 * 100;  // every point 5 cm of pose sigma
  ASSERT_TRUE(map.fuse(0, 0, m, 0, 0));
  ASSERT_TRUE(map.fuse(0, 0, m, 1, 0));
  double h = 0, s = 0;
  ASSERT_TRUE(map.estimate(0, 0, h, s));
  EXPECT_NEAR(s, 0.05, 1e-3);  // 200 points, still 5 cm
}

TEST(DemMap, MaxTilesBoundsTheMemory) {
  DemParams p;
  p.tile_cells = 8;
  p.max_tiles = 2;
  DemMap map(p);
  EXPECT_TRUE(map.fuse(0, 0, measurement(0, 1, 1, 0), 0, 0));
  EXPECT_TRUE(map.fuse(8, 0, measurement(0, 1, 1, 0), 0, 0));
  EXPECT_FALSE(map.fuse(16, 0, measurement(0, 1, 1, 0), 0, 0));
  EXPECT_EQ(map.numTiles(), 2);
}

TEST(DemMap, RasterIsNorthUpWithNanWhereEmpty) {
  DemParams p;
  p.tile_cells = 8;
  p.min_sigma_m = 0.0;
  DemMap map(p);
  ASSERT_TRUE(map.fuse(-1, -1, measurement(3.0, 0.1, 1, 200), 0, 0));
  ASSERT_TRUE(map.fuse(8, 9, measurement(-2.0, 0.1, 1, 50), 0, 0));
  DemRaster r;
  ASSERT_TRUE(map.toRaster(r));
  EXPECT_EQ(r.i0, -8);
  EXPECT_EQ(r.j0, -8);
  EXPECT_EQ(r.cols, 24);
  EXPECT_EQ(r.rows, 24);
  int col = 0, row = 0;
  ASSERT_TRUE(r.cellToPixel(-1, -1, col, row));
  EXPECT_EQ(col, 7);
  EXPECT_EQ(row, 16);  // j = -1 is the 8th row from the bottom
  EXPECT_FLOAT_EQ(r.height_m[r.index(col, row)], 3.0f);
  EXPECT_EQ(r.luminance[r.index(col, row)], 200);
  ASSERT_TRUE(r.cellToPixel(8, 9, col, row));
  EXPECT_FLOAT_EQ(r.height_m[r.index(col, row)], -2.0f);
  EXPECT_TRUE(std::isnan(r.height_m[r.index(0, 0)]));
  EXPECT_EQ(r.count[r.index(0, 0)], 0.0f);
}

// A diverged trajectory leaves a few tiles kilometres apart: their bounding box is not
// allocated, the error names the bound.
TEST(DemMap, RasterLargerThanTheBoundIsRefusedWithoutAllocating) {
  DemParams p;
  p.tile_cells = 64;
  p.max_raster_mcells = 1;
  DemMap map(p);
  ASSERT_TRUE(map.fuse(0, 0, measurement(1.0, 0.1, 1, 100), 0, 0));
  ASSERT_TRUE(map.fuse(64 * 15, 64 * 15, measurement(1.0, 0.1, 1, 100), 0, 0));  // 1024^2 cells
  DemRaster r;
  const Status s = map.toRaster(r);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("max_raster_mcells"), std::string::npos) << s.message();
  EXPECT_EQ(r.cols * r.rows, 0);
  DemMap small(p);  // 15 x 15 tiles = 921 600 cells: within the bound
  ASSERT_TRUE(small.fuse(0, 0, measurement(1.0, 0.1, 1, 100), 0, 0));
  ASSERT_TRUE(small.fuse(64 * 14, 64 * 14, measurement(1.0, 0.1, 1, 100), 0, 0));
  EXPECT_TRUE(small.toRaster(r));
  EXPECT_EQ(r.cols, 960);
}

}  // namespace
}  // namespace svslam::map

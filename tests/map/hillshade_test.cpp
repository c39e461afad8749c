// Hillshade (Horn's method) against the analytic shade of planes: n . s with the plane's normal
// and the sun's direction (azimuth 315 deg from north, altitude 45 deg).
#include "map/hillshade.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace svslam::map {
namespace {

// A rows x cols raster of the plane z = a x + b y (x east, y north, cell centres), m.
DemRaster plane(int cols, int rows, double cell_m, double a, double b) {
  DemRaster r;
  r.cell_m = cell_m;
  r.i0 = -3;
  r.j0 = 5;
  r.resize(cols, rows);
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const int i = r.i0 + col, j = r.j0 + rows - 1 - row;
      const double x = (i + 0.5) * cell_m, y = (j + 0.5) * cell_m;
      r.height_m[r.index(col, row)] = static_cast<float>(a * x + b * y);
    }
  return r;
}

// 1 + 254 * max(0, n . s) for the plane z = a x + b y, rounded.
int analyticShade(double a, double b) {
  const double k = std::numbers::pi / 180.0;
  const double az = 315 * k, alt = 45 * k;
  const double s =
      (std::sin(alt) - a * std::sin(az) * std::cos(alt) - b * std::cos(az) * std::cos(alt)) /
      std::sqrt(1 + a * a + b * b);
  return static_cast<int>(std::lround(1 + 254 * std::max(0.0, s)));
}

void expectPlane(double a, double b, int expected) {
  const DemRaster dem = plane(6, 5, 0.25, a, b);
  auto shade = hillshade(dem);
  ASSERT_TRUE(shade.isOk()) << shade.status().message();
  ASSERT_EQ(shade->size(), 30u);
  for (int row = 0; row < dem.rows; ++row)
    for (int col = 0; col < dem.cols; ++col) {
      const bool border = row == 0 || col == 0 || row == dem.rows - 1 || col == dem.cols - 1;
      EXPECT_EQ((*shade)[dem.index(col, row)], border ? 0 : expected)
          << "a " << a << " b " << b << " col " << col << " row " << row;
    }
}

TEST(Hillshade, FlatGroundIs181) { expectPlane(0, 0, 181); }

TEST(Hillshade, SlopeFacingTheSunIsFullyLit) {
  // The normal (-a, -b, 1) / |.| equals the sun direction (-1/2, 1/2, sqrt(2)/2): a = -b = 1/sqrt2.
  expectPlane(std::sqrt(0.5), -std::sqrt(0.5), 255);
}

TEST(Hillshade, SteepSlopeAwayFromTheSunIsInShadow) { expectPlane(-2.0, 2.0, 1); }

TEST(Hillshade, SlopesMatchTheAnalyticShade) {
  // Rising to the east: facing west, lit more (the sun is in the north-west); rising to the
  // north: facing south, lit less.
  expectPlane(0.5, 0, analyticShade(0.5, 0));
  expectPlane(0, 0.5, analyticShade(0, 0.5));
  expectPlane(0.3, -0.2, analyticShade(0.3, -0.2));
  EXPECT_EQ(analyticShade(0.5, 0), 218);  // 1 + 254 (sqrt(1/2) + 1/4) / sqrt(1.25)
  EXPECT_EQ(analyticShade(0, 0.5), 105);  // 1 + 254 (sqrt(1/2) - 1/4) / sqrt(1.25)
}

TEST(Hillshade, NoDataAndItsNeighboursAreZero) {
  DemRaster dem = plane(7, 7, 0.1, 0, 0);
  dem.height_m[dem.index(3, 3)] = NAN;
  auto shade = hillshade(dem);
  ASSERT_TRUE(shade.isOk());
  for (int row = 1; row < 6; ++row)
    for (int col = 1; col < 6; ++col) {
      const bool near = std::abs(row - 3) <= 1 && std::abs(col - 3) <= 1;
      EXPECT_EQ((*shade)[dem.index(col, row)], near ? 0 : 181) << col << " " << row;
    }
}

TEST(Hillshade, ZFactorAndCellSizeScaleTheSlope) {
  // Doubling z_factor on a slope of 0.25 equals a slope of 0.5 at z_factor 1.
  HillshadeParams p;
  p.z_factor = 2;
  auto shade = hillshade(plane(3, 3, 0.5, 0.25, 0), p);
  ASSERT_TRUE(shade.isOk());
  EXPECT_EQ((*shade)[4], analyticShade(0.5, 0));
}

TEST(Hillshade, BadInputIsAnError) {
  DemRaster dem = plane(3, 3, 0.1, 0, 0);
  dem.height_m.pop_back();
  EXPECT_FALSE(hillshade(dem).isOk());
  dem = plane(3, 3, 0.1, 0, 0);
  dem.cell_m = 0;
  EXPECT_FALSE(hillshade(dem).isOk());
  HillshadeParams p;
  p.altitude_deg = 91;
  EXPECT_FALSE(hillshade(plane(3, 3, 0.1, 0, 0), p).isOk());
  p = {};
  p.z_factor = NAN;
  EXPECT_FALSE(hillshade(plane(3, 3, 0.1, 0, 0), p).isOk());
  // Empty and tiny rasters are fine: all border.
  auto empty = hillshade(plane(0, 0, 0.1, 0, 0));
  ASSERT_TRUE(empty.isOk());
  EXPECT_TRUE(empty->empty());
  auto tiny = hillshade(plane(2, 1, 0.1, 0, 0));
  ASSERT_TRUE(tiny.isOk());
  EXPECT_EQ(*tiny, std::vector<std::uint8_t>(2, 0));
}

TEST(Hillshade, HugeStepIsShadowNotACrash) {
  DemRaster dem = plane(3, 3, 0.1, 0, 0);
  dem.height_m[dem.index(2, 1)] = 3e38f;
  dem.height_m[dem.index(0, 1)] = -3e38f;
  auto shade = hillshade(dem);
  ASSERT_TRUE(shade.isOk());
  EXPECT_GE((*shade)[4], 1);
}

}  // namespace
}  // namespace svslam::map

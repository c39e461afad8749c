// DemReplacer: whole-cell moves reproduce the cells, the identity the map, and a map fused from
// drifted poses comes back onto the terrain when re-placed with the inverse drift (against the
// same terrain fused from the true poses).
#include "map/dem_replacer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "map/map_frame.hpp"

namespace svslam::map {
namespace {

CellMeasurement point(double h, double sigma, int lum) {
  CellMeasurement m;
  m.sum_w = 1.0 / (sigma * sigma);
  m.sum_wh = m.sum_w * h;
  m.sum_var_pose = 0.0004;
  m.count = 1;
  m.sum_luminance = static_cast<std::uint32_t>(lum);
  return m;
}

DemParams sourcedParams() {
  DemParams p;
  p.tile_cells = 8;
  p.cell_m = 0.1;
  p.keep_cell_sources = true;
  return p;
}

Eigen::Isometry3d translation(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

TEST(DemReplacer, CellsRememberTheirLatestFusion) {
  DemMap map(sourcedParams());
  ASSERT_TRUE(map.fuse(1, 1, point(1.0, 0.2, 10), 4, 0));
  ASSERT_TRUE(map.fuse(1, 1, point(1.1, 0.1, 10), 7, 0));
  ASSERT_TRUE(map.fuse(1, 1, point(1.2, 0.3, 10), 9, 0));  // the latest: the source
  const DemTile* t = map.tile(0, 0);
  ASSERT_NE(t, nullptr);
  ASSERT_EQ(t->sources.size(), 64u);
  EXPECT_EQ(t->sources[1 * 8 + 1], 9);
  EXPECT_EQ(t->sources[0], -1);
  EXPECT_EQ(map.bytes(), 64u * (12u + 4u));
  DemParams plain = sourcedParams();
  plain.keep_cell_sources = false;
  DemMap no_sources(plain);
  ASSERT_TRUE(no_sources.fuse(1, 1, point(1.0, 0.2, 10), 4, 0));
  EXPECT_TRUE(no_sources.tile(0, 0)->sources.empty());
}

TEST(DemReplacer, WholeCellMovesReproduceEachCell) {
  DemMap map(sourcedParams());
  auto h_of = [](int i, int j) { return 0.01 * i + 0.02 * j; };
  for (int j = -3; j <= 9; ++j)
    for (int i = -5; i <= 12; ++i)
      ASSERT_TRUE(map.fuse(i, j, point(h_of(i, j), 0.05 + 0.001 * (i + 5), 50 + i), i < 4 ? 0 : 1,
                           0));
  // Fusion 0 (i < 4) moves by (-2, +1) cells and up 0.5 m, fusion 1 by (+3, -2) cells, down.
  const std::vector<Eigen::Isometry3d> C = {translation(-0.2, 0.1, 0.5),
                                            translation(0.3, -0.2, -0.25)};
  DemReplacer replacer({}, Eigen::Matrix3d::Identity());
  ASSERT_TRUE(replacer.initStatus().isOk());
  DemMap out(sourcedParams());
  DemReplaceStats st;
  ASSERT_TRUE(replacer.process(map, C, out, st).isOk());
  EXPECT_EQ(st.cells_in, 13 * 18);
  EXPECT_EQ(st.cells_out, st.cells_in);
  EXPECT_EQ(st.cells_no_source, 0);
  EXPECT_NEAR(st.max_shift_m, std::hypot(0.3, 0.2), 1e-9);
  for (int j = -3; j <= 9; ++j) {
    for (int i = -5; i <= 12; ++i) {
      const bool first = i < 4;
      const int oi = i + (first ? -2 : 3), oj = j + (first ? 1 : -2);
      double h = 0, s = 0, ho = 0, so = 0;
      ASSERT_TRUE(map.estimate(i, j, h, s));
      ASSERT_TRUE(out.estimate(oi, oj, ho, so)) << i << " " << j;
      EXPECT_NEAR(ho, h + (first ? 0.5 : -0.25), 1e-5);
      EXPECT_NEAR(so, s, 1e-3 * s);
      EXPECT_EQ(out.cell(oi, oj)->count, 1);
      EXPECT_EQ(out.cell(oi, oj)->luminance_8_8, map.cell(i, j)->luminance_8_8);
    }
  }
}

TEST(DemReplacer, IdentityReproducesTheMapInATiltedMapFrame) {
  Eigen::Matrix3d R_map_world;
  ASSERT_TRUE(mapRotationFromGravity({0.1, 0.3, 1.0}, R_map_world).isOk());
  DemMap map(sourcedParams());
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 20; ++i)
      ASSERT_TRUE(map.fuse(i, j, point(std::sin(0.3 * i) + 0.1 * j, 0.04, 90), (i + j) % 3, 0));
  const std::vector<Eigen::Isometry3d> C(3, Eigen::Isometry3d::Identity());
  DemReplacer replacer({}, R_map_world);
  DemMap out(sourcedParams());
  DemReplaceStats st;
  ASSERT_TRUE(replacer.process(map, C, out, st).isOk());
  EXPECT_EQ(st.cells_out, 400);
  EXPECT_LT(st.max_shift_m, 1e-9);
  for (int j = 0; j < 20; ++j) {
    for (int i = 0; i < 20; ++i) {
      double h = 0, s = 0, ho = 0, so = 0;
      ASSERT_TRUE(map.estimate(i, j, h, s));
      ASSERT_TRUE(out.estimate(i, j, ho, so));
      EXPECT_NEAR(ho, h, 1e-5);
      EXPECT_NEAR(so, s, 1e-3 * s);
    }
  }
}

// Terrain z = f(x, y) over 20 m x 20 m; each 2 m strip in x is "seen" by one fusion whose pose
// drifted by D_s (a point P is fused at D_s P), growing with s in x, y, z and yaw. Points every
// 0.02 m (25 a cell).
double terrain(double x, double y) { return 2.0 * std::sin(0.3 * x) + std::cos(0.2 * y); }

Eigen::Isometry3d drift(int s) {
  Eigen::Isometry3d D = translation(0.05 * s, -0.03 * s, 0.02 * s);
  D.linear() = Eigen::AngleAxisd(0.002 * s, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return D;
}

void fuseTerrain(DemMap& map, bool drifted) {
  const double cell = map.params().cell_m;
  for (int s = 0; s < 10; ++s) {
    const Eigen::Isometry3d D = drifted ? drift(s) : Eigen::Isometry3d::Identity();
    for (double y = 0.01; y < 20.0; y += 0.02) {
      for (double x = 2.0 * s + 0.01; x < 2.0 * s + 2.0; x += 0.02) {
        const Eigen::Vector3d P = D * Eigen::Vector3d(x, y, terrain(x, y));
        const int i = static_cast<int>(std::floor(P.x() / cell));
        const int j = static_cast<int>(std::floor(P.y() / cell));
        ASSERT_TRUE(map.fuse(i, j, point(P.z(), 0.05, 100), s, 0));
      }
    }
  }
}

// RMS of (cell height - terrain at the cell centre) over the cells inside [1, 19] m^2 (away
// from the borders, which the drift moves); `cells` counts them.
double rmsAgainstTerrain(const DemMap& map, int& cells) {
  const double cell = map.params().cell_m;
  double sum = 0.0;
  cells = 0;
  for (int j = 10; j < 190; ++j) {
    for (int i = 10; i < 190; ++i) {
      double h = 0, s = 0;
      if (!map.estimate(i, j, h, s)) continue;
      const double e = h - terrain((i + 0.5) * cell, (j + 0.5) * cell);
      sum += e * e;
      ++cells;
    }
  }
  return cells > 0 ? std::sqrt(sum / cells) : INFINITY;
}

TEST(DemReplacer, DriftedMapComesBackOntoTheTerrain) {
  DemMap truth(sourcedParams()), drifted(sourcedParams());
  fuseTerrain(truth, false);
  fuseTerrain(drifted, true);
  std::vector<Eigen::Isometry3d> C;
  for (int s = 0; s < 10; ++s) C.push_back(drift(s).inverse());
  DemReplacer replacer({}, Eigen::Matrix3d::Identity());
  DemMap replaced(sourcedParams());
  DemReplaceStats st;
  ASSERT_TRUE(replacer.process(drifted, C, replaced, st).isOk());
  int n_truth = 0, n_drifted = 0, n_replaced = 0;
  const double e_truth = rmsAgainstTerrain(truth, n_truth);
  const double e_drifted = rmsAgainstTerrain(drifted, n_drifted);
  const double e_replaced = rmsAgainstTerrain(replaced, n_replaced);
  EXPECT_GT(st.max_shift_m, 0.4);
  EXPECT_GT(e_drifted, 0.1);
  std::printf("height RMS against the terrain: true poses %.5f m, drifted %.5f m, re-placed %.5f m\n",
              e_truth, e_drifted, e_replaced);
  EXPECT_LT(e_replaced, 0.05 * e_drifted);
  // The points of a drifted cell are not centred in it (the 0.02 m sampling against drifts that
  // are not multiples of it: up to 0.01 m off on slopes up to 0.6), so each re-placed cell is the
  // terrain a few millimetres away from its centre.
  EXPECT_LT(e_replaced, 0.004);
  EXPECT_GE(n_replaced, n_truth - n_truth / 100);
}

TEST(DemReplacer, BadInputIsNamed) {
  DemReplacerParams bad;
  bad.min_coverage = 0.0;
  EXPECT_FALSE(DemReplacer(bad, Eigen::Matrix3d::Identity()).initStatus().isOk());
  EXPECT_FALSE(DemReplacer({}, 2.0 * Eigen::Matrix3d::Identity()).initStatus().isOk());

  DemReplacer replacer({}, Eigen::Matrix3d::Identity());
  DemParams plain = sourcedParams();
  plain.keep_cell_sources = false;
  DemMap no_sources(plain), out(sourcedParams());
  DemReplaceStats st;
  const Status s = replacer.process(no_sources, {}, out, st);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.message().find("cell sources"), std::string::npos) << s.message();

  DemMap map(sourcedParams());
  ASSERT_TRUE(map.fuse(0, 0, point(1.0, 0.1, 10), 0, 0));
  Eigen::Isometry3d nan = Eigen::Isometry3d::Identity();
  nan.translation().x() = NAN;
  EXPECT_EQ(replacer.process(map, {nan}, out, st).code(), StatusCode::kInvalidArgument);
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 1.1;
  EXPECT_EQ(replacer.process(map, {scaled}, out, st).code(), StatusCode::kInvalidArgument);
  DemParams other = sourcedParams();
  other.cell_m = 0.2;
  DemMap coarse(other);
  EXPECT_EQ(replacer.process(map, {}, coarse, st).code(), StatusCode::kInvalidArgument);
  // A source without a correction stays where it was, counted.
  ASSERT_TRUE(replacer.process(map, {}, out, st).isOk());
  EXPECT_EQ(st.cells_no_source, 1);
  double h = 0, sg = 0;
  EXPECT_TRUE(out.estimate(0, 0, h, sg));
  EXPECT_NEAR(h, 1.0, 1e-6);
}

}  // namespace
}  // namespace svslam::map

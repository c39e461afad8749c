// Ground truth of the elevation map of the synthetic flight: the source's gravity makes the map
// z axis the world's vertical; the cell under the first camera has the terrain height below it;
// far cells are unseen; counts are bounded by the frames; a full flight is fast.
#include "drivers/synthetic/synthetic_dem.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "drivers/source/stereo_source.hpp"
#include "map/map_frame.hpp"

namespace svslam::drivers {
namespace {

struct Flight {
  std::unique_ptr<StereoSource> source;
  const SyntheticFlight* flight = nullptr;
  Eigen::Matrix3d R_map_world;
};

Flight openFlight(const std::string& options) {
  Flight s;
  auto src = openSyntheticSource(options);
  EXPECT_TRUE(src.isOk()) << src.status().message();
  s.source = std::move(*src);
  s.flight = asSyntheticFlight(*s.source);
  Eigen::Vector3d g;
  EXPECT_TRUE(s.source->gravityInFirstCamera(g));
  EXPECT_TRUE(map::mapRotationFromGravity({g.x(), g.y(), g.z()}, s.R_map_world));
  return s;
}

map::DemRaster window(double cell_m, int i0, int j0, int cols, int rows) {
  map::DemRaster r;
  r.cell_m = cell_m;
  r.i0 = i0;
  r.j0 = j0;
  r.cols = cols;
  r.rows = rows;
  return r;
}

}  // namespace

TEST(SyntheticDem, GravityMakesMapZTheWorldVertical) {
  for (const char* options : {"", "variant=rover", "camera_pitch_deg=40,wobble_deg=10"}) {
    Flight s = openFlight(options);
    ASSERT_NE(s.flight, nullptr);
    Eigen::Vector3d g;
    ASSERT_TRUE(s.source->gravityInFirstCamera(g));
    EXPECT_NEAR(g.norm(), 1.0, 1e-12);
    const Eigen::Matrix3d R_W_C0 = s.flight->pose(0).linear();
    EXPECT_LT((R_W_C0 * g - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12) << options;
    const Eigen::Matrix3d R_W_map = R_W_C0 * s.R_map_world.transpose();
    EXPECT_LT((R_W_map.col(2) - Eigen::Vector3d::UnitZ()).norm(), 1e-12) << options;
  }
}

TEST(SyntheticDem, CellUnderFirstCameraHasTheTerrainHeight) {
  Flight s = openFlight("frames=20,width=320,height=240");
  // 8 x 8 cells of 0.05 m around the map origin (the first camera centre).
  map::DemRaster r = window(0.05, -4, -4, 8, 8);
  ASSERT_TRUE(syntheticGroundTruthDem(*s.flight, 20, s.R_map_world, r));
  const Eigen::Vector3d c0 = s.flight->pose(0).translation();
  const Eigen::Matrix3d R_W_map = s.flight->pose(0).linear() * s.R_map_world.transpose();
  int col = 0, row = 0;
  ASSERT_TRUE(r.cellToPixel(0, 0, col, row));
  const std::size_t k = r.index(col, row);
  // Cell (0, 0): centre (0.025, 0.025) in the map, exactly.
  const Eigen::Vector3d centre_W = c0 + R_W_map * Eigen::Vector3d(0.025, 0.025, 0.0);
  const double expected = s.flight->heightAt(centre_W.x(), centre_W.y()) - c0.z();
  EXPECT_NEAR(r.height_m[k], expected, 1e-5);
  // And within the terrain slope of the height straight below c0.
  EXPECT_NEAR(r.height_m[k], s.flight->heightAt(c0.x(), c0.y()) - c0.z(), 0.05);
  EXPECT_LT(r.height_m[k], -20.0);  // the blimp flies 25-30 m above the datum
  EXPECT_EQ(r.sigma_m[k], 0.0f);
  EXPECT_GE(r.count[k], 1.0f);  // frame 0 sees it in both images
  EXPECT_LE(r.count[k], 20.0f);
  for (std::size_t m = 0; m < r.height_m.size(); ++m) EXPECT_TRUE(std::isfinite(r.height_m[m]));
}

TEST(SyntheticDem, FarCellsAreUnseenAndCountsAreBounded) {
  Flight s = openFlight("frames=30,width=320,height=240");
  map::DemRaster far = window(0.5, 4000, 4000, 10, 10);  // 2 km away
  ASSERT_TRUE(syntheticGroundTruthDem(*s.flight, 30, s.R_map_world, far));
  for (std::size_t k = 0; k < far.height_m.size(); ++k) {
    EXPECT_TRUE(std::isnan(far.height_m[k]));
    EXPECT_TRUE(std::isnan(far.sigma_m[k]));
    EXPECT_EQ(far.count[k], 0.0f);
  }
  map::DemRaster r = window(0.5, -120, -120, 240, 240);  // the whole loop and beyond
  ASSERT_TRUE(syntheticGroundTruthDem(*s.flight, 30, s.R_map_world, r));
  int seen = 0, unseen = 0;
  for (std::size_t k = 0; k < r.height_m.size(); ++k) {
    EXPECT_GE(r.count[k], 0.0f);
    EXPECT_LE(r.count[k], 30.0f);
    EXPECT_EQ(r.luminance[k], 0);
    if (std::isnan(r.height_m[k])) {
      EXPECT_EQ(r.count[k], 0.0f);
      ++unseen;
    } else {
      EXPECT_LE(std::fabs(r.height_m[k] + s.flight->pose(0).translation().z()),
                s.flight->maxAbsHeight() + 1e-6);
      ++seen;
    }
  }
  EXPECT_GT(seen, 100);
  EXPECT_GT(unseen, 100);  // the window's corners, 60 m from the origin
}

// The footprint boxes skip no cell: same result as projecting every cell in every frame.
TEST(SyntheticDem, SameAsProjectingEveryCell) {
  for (const char* options : {"frames=12,width=160,height=120",
                              "variant=rover,frames=12,width=160,height=120,max_range_m=40"}) {
    Flight s = openFlight(options);
    map::DemRaster r = window(0.5, -80, -80, 160, 160);
    ASSERT_TRUE(syntheticGroundTruthDem(*s.flight, 12, s.R_map_world, r));
    const Eigen::Vector3d c0 = s.flight->pose(0).translation();
    const Eigen::Matrix3d R_W_map = s.flight->pose(0).linear() * s.R_map_world.transpose();
    const StereoCalibration& cal = s.flight->calibration();
    const double range = s.flight->params().max_range_m;
    int seen = 0;
    for (int row = 0; row < r.rows; ++row) {
      for (int col = 0; col < r.cols; ++col) {
        const Eigen::Vector3d m((r.i0 + col + 0.5) * 0.5, (r.j0 + r.rows - 1 - row + 0.5) * 0.5, 0);
        Eigen::Vector3d P = c0 + R_W_map * m;
        P.z() = s.flight->heightAt(P.x(), P.y());
        bool in_left = false;
        int both = 0;
        for (int k = 0; k < 12; ++k) {
          const Eigen::Isometry3d T = s.flight->pose(k);
          const Eigen::Vector3d p = T.inverse() * P;
          if (p.z() <= 0 || (P - T.translation()).norm() > range) continue;
          auto inside = [&](double x) {
            const double u = cal.f_px * x / p.z() + cal.cx_px;
            const double v = cal.f_px * p.y() / p.z() + cal.cy_px;
            return u >= -0.5 && u < cal.width - 0.5 && v >= -0.5 && v < cal.height - 0.5;
          };
          if (!inside(p.x())) continue;
          in_left = true;
          both += inside(p.x() - cal.baseline_m) ? 1 : 0;
        }
        const std::size_t k = r.index(col, row);
        ASSERT_EQ(!std::isnan(r.height_m[k]), in_left) << options << " " << col << " " << row;
        ASSERT_EQ(r.count[k], static_cast<float>(both)) << options << " " << col << " " << row;
        if (in_left) {
          EXPECT_NEAR(r.height_m[k], P.z() - c0.z(), 1e-4);
          ++seen;
        }
      }
    }
    EXPECT_GT(seen, 50) << options;
  }
}

TEST(SyntheticDem, BadArgumentsAreRejected) {
  Flight s = openFlight("frames=10,width=320,height=240");
  map::DemRaster r = window(0.1, 0, 0, 4, 4);
  EXPECT_FALSE(syntheticGroundTruthDem(*s.flight, 0, s.R_map_world, r));
  EXPECT_FALSE(syntheticGroundTruthDem(*s.flight, 11, s.R_map_world, r));
  EXPECT_FALSE(syntheticGroundTruthDem(*s.flight, 10, Eigen::Matrix3d::Identity(), r));  // tilted
  map::DemRaster empty = window(0.1, 0, 0, 0, 4);
  EXPECT_FALSE(syntheticGroundTruthDem(*s.flight, 10, s.R_map_world, empty));
  map::DemRaster nan_cell = window(NAN, 0, 0, 4, 4);
  EXPECT_FALSE(syntheticGroundTruthDem(*s.flight, 10, s.R_map_world, nan_cell));
}

// The whole default flight (its time is printed for information; speed targets live in
// benchmarks, not in unit tests): every cell is seen by at most the flight's 100 frames.
TEST(SyntheticDem, FullBlimpFlightCountsAreBounded) {
  Flight s = openFlight("");  // 100 frames, 1024 x 768, 25-30 m, 70 m loop
  map::DemRaster r = window(0.1, -400, -400, 800, 800);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(syntheticGroundTruthDem(*s.flight, s.flight->size(), s.R_map_world, r));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("ground-truth DEM, 100 frames, 800 x 800 cells: %.3f s\n", seconds);
  double max_count = 0;
  for (float c : r.count) max_count = std::max(max_count, static_cast<double>(c));
  EXPECT_GT(max_count, 10.0);
  EXPECT_LE(max_count, 100.0);
}

}  // namespace svslam::drivers

// svslam eval-dem end to end: two small DEMs written with the GeoTIFF writer, the JSON numbers,
// and clear errors with a non-zero exit for missing, corrupt or mismatched files; the path mode
// on a tilted road and a straight KITTI trajectory.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli_helpers.hpp"
#include "drivers/files/dem_files.hpp"

namespace fs = std::filesystem;
using svslam::test::slurp;

namespace {

svslam::map::DemRaster row4(std::initializer_list<float> h) {
  svslam::map::DemRaster r;
  r.cell_m = 0.5;
  r.i0 = -2;
  r.j0 = 7;
  r.resize(4, 1);
  auto it = h.begin();
  for (std::size_t k = 0; k < 4; ++k, ++it) {
    r.height_m[k] = *it;
    r.sigma_m[k] = std::isfinite(*it) ? 0.1f : NAN;
  }
  return r;
}

class CliEvalDem : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = svslam::test::freshTestDir("svslam_cli_dem_");
    svslam::map::DemRaster gt = row4({0, 0, 0, 0});
    gt.count = {2, 5, 0, 0};  // seen by both cameras: the first two cells
    svslam::map::DemRaster est = row4({0.1f, -0.3f, 0.5f, NAN});
    est.sigma_m[1] = 0.2f;
    ASSERT_TRUE(svslam::drivers::writeDemGeoTiff(path("gt.tif"), gt).isOk());
    ASSERT_TRUE(svslam::drivers::writeDemGeoTiff(path("dem.tif"), est).isOk());
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  int run(const std::string& args, std::string& out, std::string& err) const {
    const int code = svslam::test::runSvslam(args, dir_ / "out.txt", dir_ / "err.txt");
    out = slurp(dir_ / "out.txt");
    err = slurp(dir_ / "err.txt");
    return code;
  }
  void expectError(const std::string& args, const std::string& needle) const {
    std::string out, err;
    const int code = run(args, out, err);
    EXPECT_TRUE(code == 1 || code == 2) << args << " exited " << code << "\n" << err;
    EXPECT_NE(err.find(needle), std::string::npos) << args << "\nstderr: " << err;
    EXPECT_TRUE(out.empty()) << out;
  }
  fs::path dir_;
};

TEST_F(CliEvalDem, PrintsTheScoreAsJson) {
  std::string out, err;
  ASSERT_EQ(run("eval-dem --dem " + path("dem.tif") + " --gt " + path("gt.tif"), out, err), 0)
      << err;
  // Errors +0.1, -0.3, +0.5 on 3 of 4 cells; sigma 0.1, 0.2, 0.1: 2 of 3 within 2 sigma.
  for (const char* field :
       {"\"gt_cells\": 4", "\"est_cells\": 3", "\"common_cells\": 3", "\"rmse_m\": 0.3416",
        "\"median_abs_m\": 0.3000", "\"bias_m\": 0.1000", "\"coverage\": 0.7500",
        "\"within_2sigma\": 0.6667", "\"gt_stereo_cells\": 2", "\"coverage_stereo\": 1.0000"})
    EXPECT_NE(out.find(field), std::string::npos) << field << " in " << out;
  EXPECT_EQ(out.front(), '{');
  EXPECT_EQ(out.substr(out.size() - 2), "}\n");
  EXPECT_TRUE(err.empty()) << err;
}

TEST_F(CliEvalDem, HelpAndBadInput) {
  std::string out, err;
  EXPECT_EQ(run("eval-dem --help", out, err), 0);
  EXPECT_NE(out.find("--dem"), std::string::npos);
  EXPECT_NE(out.find("--gt"), std::string::npos);
  EXPECT_EQ(run("--help", out, err), 0);
  EXPECT_NE(out.find("eval-dem"), std::string::npos);

  expectError("eval-dem --dem " + path("dem.tif"), "--gt");
  expectError("eval-dem --dem " + path("none.tif") + " --gt " + path("gt.tif"), "none.tif");
  std::ofstream(path("junk.tif")) << "junk";
  expectError("eval-dem --dem " + path("dem.tif") + " --gt " + path("junk.tif"), "not a GeoTIFF");
  const std::string bytes = slurp(path("gt.tif"));
  std::ofstream(path("cut.tif"), std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  expectError("eval-dem --dem " + path("cut.tif") + " --gt " + path("gt.tif"), "cut.tif");
  svslam::map::DemRaster coarse = row4({0, 0, 0, 0});
  coarse.cell_m = 1.0;
  ASSERT_TRUE(svslam::drivers::writeDemGeoTiff(path("coarse.tif"), coarse).isOk());
  expectError("eval-dem --dem " + path("coarse.tif") + " --gt " + path("gt.tif"), "cell size");
  ASSERT_TRUE(svslam::drivers::writeOrthoTiff(path("ortho.tif"), coarse).isOk());
  expectError("eval-dem --dem " + path("ortho.tif") + " --gt " + path("gt.tif"), "band count");
}

// A road z = 0.05 y - 1.65 m in 0.5 m cells over x in [-2, 2], y in [-1, 5] (map frame), and a
// KITTI trajectory driving 4 m along the camera's z; gravity 0,1,0 (camera y down) makes the
// map's y the camera's z, so the path is (0, 0..4, 0) in the map.
class CliEvalDemPath : public CliEvalDem {
 protected:
  void SetUp() override {
    CliEvalDem::SetUp();
    svslam::map::DemRaster road;
    road.cell_m = 0.5;
    road.i0 = -4;
    road.j0 = -2;
    road.resize(8, 12);
    for (int r = 0; r < road.rows; ++r) {
      for (int c = 0; c < road.cols; ++c) {
        const double y = (road.j0 + road.rows - 1 - r + 0.5) * road.cell_m;
        road.height_m[road.index(c, r)] = static_cast<float>(0.05 * y - 1.65);
        road.sigma_m[road.index(c, r)] = 0.1f;
        road.count[road.index(c, r)] = 3;
      }
    }
    road.height_m[road.index(7, 5)] = 100.0f;  // (1.75, 2.25): beside the strip
    ASSERT_TRUE(svslam::drivers::writeDemGeoTiff(path("road.tif"), road).isOk());
    std::ofstream traj(path("traj.txt"));
    for (int k = 0; k <= 4; ++k) traj << "1 0 0 0 0 1 0 0 0 0 1 " << k << "\n";
  }
  std::string pathArgs(const std::string& extra) const {
    return "eval-dem --dem " + path("road.tif") + " --path " + path("traj.txt") +
           " --gravity 0,1,0 " + extra;
  }
};

TEST_F(CliEvalDemPath, PrintsTheFlatnessOfThePathStrip) {
  std::string out, err;
  ASSERT_EQ(run(pathArgs(""), out, err), 0) << err;
  // Within 1 m of x = 0, y in [0, 4]: 4 columns x 8 rows, and 4 + 2 cells on each cap.
  // The camera is 1.65 - 0.05 y above the road: 1.55 m on average over y = 0..4.
  for (const char* field :
       {"\"strip_cells\": 44", "\"path_length_m\": 4.000", "\"half_width_m\": 1.000",
        "\"plane_residual_std_m\": 0.0000", "\"plane_residual_p95_abs_m\": 0.0000",
        "\"median_sigma_m\": 0.1000", "\"camera_height_above_plane_m\": 1.5500"})
    EXPECT_NE(out.find(field), std::string::npos) << field << " in " << out;
  EXPECT_EQ(out.find("\"height_std_m\": 0.0000"), std::string::npos) << out;  // the slope
  EXPECT_TRUE(err.empty()) << err;

  // Without the first 2 m: y in [2, 4], 4 x 4 cells and 6 on each cap; the camera 1.5 m above.
  ASSERT_EQ(run(pathArgs("--min-ahead-m 2"), out, err), 0) << err;
  for (const char* field : {"\"strip_cells\": 28", "\"path_length_m\": 2.000",
                            "\"camera_height_above_plane_m\": 1.5000"})
    EXPECT_NE(out.find(field), std::string::npos) << field << " in " << out;
}

TEST_F(CliEvalDemPath, EmptyStripAndBadInput) {
  std::ofstream(path("far.txt")) << "1 0 0 100 0 1 0 0 0 0 1 0\n1 0 0 100 0 1 0 0 0 0 1 1\n";
  std::string out, err;
  ASSERT_EQ(run("eval-dem --dem " + path("road.tif") + " --path " + path("far.txt"), out, err), 0)
      << err;
  for (const char* field :
       {"\"strip_cells\": 0", "\"height_std_m\": null", "\"plane_residual_std_m\": null",
        "\"median_sigma_m\": null", "\"camera_height_above_plane_m\": null"})
    EXPECT_NE(out.find(field), std::string::npos) << field << " in " << out;

  expectError("eval-dem --dem " + path("road.tif"), "--path");
  expectError(pathArgs("--gt " + path("gt.tif")), "not both");
  expectError(pathArgs("").substr(0, pathArgs("").find(" --gravity")) + " --gravity 0,1",
              "--gravity");
  expectError(pathArgs("").substr(0, pathArgs("").find(" --gravity")) + " --gravity 0,0,0",
              "gravity");
  expectError(pathArgs("--half-width-m 0"), "half-width");
  expectError(pathArgs("--min-ahead-m -1"), "--min-ahead-m");
  expectError("eval-dem --dem " + path("road.tif") + " --path " + path("none.txt"), "none.txt");
}

}  // namespace

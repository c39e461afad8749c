// svslam eval-dem end to end: two small DEMs written with the GeoTIFF writer, the JSON numbers,
// and clear errors with a non-zero exit for missing, corrupt or mismatched files.
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

}  // namespace

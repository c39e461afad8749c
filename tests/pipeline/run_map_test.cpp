// The elevation map of `svslam run` end to end through the executable: its files, accuracy
// against the synthetic ground truth (a short, small flight), the same map threaded and
// sequential, and a failed write of dem.tif reported with the file's name, the previous file
// left intact.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli_helpers.hpp"
#include "drivers/files/dem_files.hpp"
#include "eval/dem_metrics.hpp"

namespace fs = std::filesystem;
using svslam::test::slurp;

namespace {

// The first 12 frames of the default flight's 100-frame loop, at 320x240.
const std::string kSource = "--source synthetic:width=320,height=240,frames=12,loop_frames=100";

class RunMap : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = svslam::test::freshTestDir("svslam_run_map_"); }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  int run(const std::string& args, std::string* err = nullptr) const {
    const int code = svslam::test::runSvslam("run " + args, path("stdout.txt"), path("stderr.txt"));
    if (err) *err = slurp(path("stderr.txt"));
    return code;
  }
  fs::path dir_;
};

TEST_F(RunMap, WritesTheMapFilesAndTheyMatchTheGroundTruth) {
  ASSERT_EQ(run(kSource + " --out " + path("a")), 0) << slurp(path("stderr.txt"));
  for (const char* f :
       {"dem.tif", "ortho.tif", "ortho.png", "dem_hillshade.png", "groundtruth_dem.tif"})
    EXPECT_TRUE(fs::exists(path("a/") + f)) << f;
  auto dem = svslam::drivers::readDemGeoTiff(path("a/dem.tif"));
  auto gt = svslam::drivers::readDemGeoTiff(path("a/groundtruth_dem.tif"));
  ASSERT_TRUE(dem.isOk()) << dem.status().message();
  ASSERT_TRUE(gt.isOk()) << gt.status().message();
  auto score = svslam::scoreDem(*dem, *gt);
  ASSERT_TRUE(score.isOk());
  // 12 frames at 320x240 (4x coarser pixels than the default flight): looser than its figures.
  EXPECT_GT(score->coverage, 0.9);
  EXPECT_LT(score->rmse_m, 0.15);
  EXPECT_LT(score->median_abs_m, 0.06);
  EXPECT_GT(score->within_2sigma, 0.85);
  const std::string stats = slurp(path("a/stats.json"));
  for (const char* key : {"\"map\"", "\"frames_fused\": 12", "\"gravity_from\": \"source\""})
    EXPECT_NE(stats.find(key), std::string::npos) << key << " missing in " << stats;
}

TEST_F(RunMap, ThreadedAndSequentialMapsAreIdentical) {
  ASSERT_EQ(run(kSource + " --out " + path("t")), 0);
  ASSERT_EQ(run(kSource + " --sequential --out " + path("s")), 0);
  for (const char* f : {"dem.tif", "ortho.png"}) {
    const std::string t = slurp(path("t/") + f), s = slurp(path("s/") + f);
    ASSERT_FALSE(t.empty()) << f;
    EXPECT_EQ(t, s) << f << " differs threaded vs sequential";
  }
}

TEST_F(RunMap, FailedDemWriteNamesTheFileAndKeepsTheOtherOutputs) {
  fs::create_directories(path("o/dem.tif"));  // a folder where the file should go
  std::string err;
  EXPECT_NE(run(kSource + " --out " + path("o"), &err), 0);
  EXPECT_NE(err.find("dem.tif"), std::string::npos) << err;
  EXPECT_TRUE(fs::is_directory(path("o/dem.tif")));
  // What was written before is kept.
  EXPECT_FALSE(slurp(path("o/trajectory_kitti.txt")).empty());
  EXPECT_FALSE(slurp(path("o/stats.json")).empty());
}

TEST_F(RunMap, MapWithoutDenseStereoIsAConfigError) {
  std::ofstream(path("c.yaml")) << "dense_stereo: {enabled: false}\n";
  std::string err;
  EXPECT_NE(run(kSource + " --config " + path("c.yaml") + " --out " + path("o"), &err), 0);
  EXPECT_NE(err.find("map.enabled"), std::string::npos) << err;
  std::ofstream(path("d.yaml")) << "dense_stereo: {enabled: false}\nmap: {enabled: false}\n";
  EXPECT_EQ(run(kSource + " --config " + path("d.yaml") + " --out " + path("p")), 0);
  EXPECT_FALSE(fs::exists(path("p/dem.tif")));
}

}  // namespace

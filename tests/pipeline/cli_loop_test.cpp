// Loop closing in `svslam run` end to end: a vocabulary trained with `svslam train-vocabulary
// --source` on one synthetic flight, then a two-lap flight over other terrain: the back end
// accepts loops (all between views of the same ground), writes trajectory_optimized_*.txt with
// one pose per published pose and dem_optimized.tif, and the result is the same threaded and
// sequential. Bad loop
// configuration gives a clear error and a non-zero exit.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_helpers.hpp"

namespace fs = std::filesystem;
using svslam::test::slurp;

namespace {

// 320x240 blimp flight, two 60-frame laps over a 150 m loop (views about 30 m wide).
const std::string kFlight =
    "synthetic:width=320,height=240,frames=120,loop_frames=60,loop_length_m=150";

class CliLoop : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = svslam::test::freshTestDir("svslam_cli_loop_");
    const int code = svslam::test::runSvslam(
        "train-vocabulary --source synthetic:seed=99,width=320,height=240,frames=12,"
        "loop_length_m=120 --frames 12 --depth 3 --out " +
            (dir_ / "v.svvoc").string(),
        dir_ / "out.txt", dir_ / "err.txt");
    ASSERT_EQ(code, 0) << slurp(dir_ / "err.txt");
    std::ofstream(dir_ / "loop.yaml") << "loop:\n  enabled: true\n  vocabulary: "
                                      << (dir_ / "v.svvoc").string()
                                      << "\n  exclude_recent: 8\n";
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static int run(const std::string& args, std::string& err) {
    const int code = svslam::test::runSvslam(args, dir_ / "out.txt", dir_ / "err.txt");
    err = slurp(dir_ / "err.txt");
    return code;
  }
  static std::vector<std::string> lines(const fs::path& p) {
    std::ifstream in(p);
    std::vector<std::string> v;
    for (std::string l; std::getline(in, l);) v.push_back(l);
    return v;
  }
  static fs::path dir_;
};
fs::path CliLoop::dir_;

TEST_F(CliLoop, TwoLapsCloseLoopsAndWriteTheOptimisedTrajectory) {
  std::string err;
  const fs::path a = dir_ / "a", b = dir_ / "b";
  ASSERT_EQ(run("run --config " + (dir_ / "loop.yaml").string() + " --source " + kFlight +
                    " --out " + a.string(),
                err),
            0)
      << err;
  const std::vector<std::string> online = lines(a / "trajectory_kitti.txt");
  const std::vector<std::string> optimised = lines(a / "trajectory_optimized_kitti.txt");
  EXPECT_EQ(online.size(), 120u);
  EXPECT_EQ(optimised.size(), online.size());
  EXPECT_EQ(lines(a / "trajectory_optimized_tum.txt").size(), online.size());
  const std::string stats = slurp(a / "stats.json");
  const std::size_t at = stats.find("\"loops_accepted\": ");
  ASSERT_NE(at, std::string::npos) << stats;
  EXPECT_GE(std::stoi(stats.substr(at + 18)), 2) << stats;
  // Every accepted loop joins two views of the same ground: camera centres (ground truth) less
  // less than 25 m apart (a view is about 31 m x 23 m on the ground).
  std::vector<Eigen::Vector3d> gt;
  for (const std::string& l : lines(a / "groundtruth_kitti.txt")) {
    std::istringstream in(l);
    double v[12];
    for (double& x : v) in >> x;
    gt.emplace_back(v[3], v[7], v[11]);
  }
  ASSERT_EQ(gt.size(), 120u);
  for (std::size_t p = stats.find("\"query_frame\": "); p != std::string::npos;
       p = stats.find("\"query_frame\": ", p + 1)) {
    const int q = std::stoi(stats.substr(p + 15));
    const std::size_t c_at = stats.find("\"candidate_frame\": ", p);
    const int c = std::stoi(stats.substr(c_at + 19));
    EXPECT_LT((gt[static_cast<std::size_t>(q)] - gt[static_cast<std::size_t>(c)]).norm(), 25.0)
        << "loop " << q << " -> " << c;
  }
  // Same output sequentially.
  ASSERT_EQ(run("run --sequential --config " + (dir_ / "loop.yaml").string() + " --source " +
                    kFlight + " --out " + b.string(),
                err),
            0)
      << err;
  EXPECT_EQ(slurp(a / "trajectory_optimized_kitti.txt"),
            slurp(b / "trajectory_optimized_kitti.txt"));
  // The estimator moved into the corrected frame (loop.feedback) at the same frames in both.
  const std::size_t fm = stats.find("\"feedback_moves\": ");
  ASSERT_NE(fm, std::string::npos) << stats;
  EXPECT_GE(std::stoi(stats.substr(fm + 18)), 1) << stats;
  EXPECT_EQ(slurp(a / "trajectory_kitti.txt"), slurp(b / "trajectory_kitti.txt"));
  EXPECT_EQ(slurp(a / "landmarks_optimized.ply"), slurp(b / "landmarks_optimized.ply"));
  EXPECT_EQ(lines(a / "landmarks_optimized.ply").size(), lines(a / "landmarks.ply").size());
  // The elevation map re-placed with the corrected trajectory, the same both ways.
  ASSERT_TRUE(fs::exists(a / "dem_optimized.tif"));
  EXPECT_TRUE(fs::exists(a / "ortho_optimized.png"));
  EXPECT_EQ(slurp(a / "dem_optimized.tif"), slurp(b / "dem_optimized.tif"));
  EXPECT_NE(stats.find("\"replaced\": {\"cells_in\": "), std::string::npos) << stats;
}

TEST_F(CliLoop, BadLoopConfigurationIsNamed) {
  std::string err;
  std::ofstream(dir_ / "novoc.yaml") << "loop:\n  enabled: true\n";
  EXPECT_NE(run("run --config " + (dir_ / "novoc.yaml").string() + " --source " + kFlight +
                    " --max-frames 2 --out " + (dir_ / "c").string(),
                err),
            0);
  EXPECT_NE(err.find("loop.vocabulary"), std::string::npos) << err;
  std::ofstream(dir_ / "missing.yaml") << "loop:\n  enabled: true\n  vocabulary: /nonexistent/v.svvoc\n";
  EXPECT_NE(run("run --config " + (dir_ / "missing.yaml").string() + " --source " + kFlight +
                    " --max-frames 2 --out " + (dir_ / "c").string(),
                err),
            0);
  EXPECT_NE(err.find("/nonexistent/v.svvoc"), std::string::npos) << err;
  std::ofstream(dir_ / "range.yaml") << "loop:\n  min_inliers: 2\n";
  EXPECT_NE(run("run --config " + (dir_ / "range.yaml").string() + " --source " + kFlight +
                    " --max-frames 2 --out " + (dir_ / "c").string(),
                err),
            0);
  EXPECT_NE(err.find("loop.min_inliers"), std::string::npos) << err;
}

}  // namespace

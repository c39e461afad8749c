// Loop closing in `svslam run` end to end: a vocabulary trained with `svslam train-vocabulary
// --source` on one synthetic flight, then a two-lap flight over other terrain: the back end
// accepts loops (all between views of the same ground), writes trajectory_optimized_*.txt with
// one pose per published pose and dem_optimized.tif, and the result is the same threaded and
// sequential. The estimator is reset during the second lap (the test hook standing in for the
// LCM reset command): the loop closer follows it into the new world and brings the first lap
// into that world through the loops across the reset. Bad loop configuration gives a clear
// error and a non-zero exit.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
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
// The estimator is reset before this frame (pipeline.fault.reset_frame): a new world frame with
// the camera at the identity.
constexpr int kResetFrame = 75;

Eigen::Isometry3d kittiPose(const std::string& line) {
  std::istringstream in(line);
  Eigen::Matrix<double, 3, 4, Eigen::RowMajor> m;
  for (int k = 0; k < 12; ++k) in >> m.data()[k];
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.matrix().topRows<3>() = m;
  return T;
}

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
                                      << "\n  exclude_recent: 8\n"
                                      << "pipeline:\n  fault:\n    reset_frame: " << kResetFrame
                                      << "\nmap:\n  replace_period_s: 0.001\n";
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
  const fs::path log = dir_ / "run.lcmlog";
  ASSERT_EQ(run("run --config " + (dir_ / "loop.yaml").string() + " --source " + kFlight +
                    " --out " + a.string() + " --lcm-url 'file://" + log.string() + "?mode=w'",
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
  std::vector<Eigen::Isometry3d> T_gt;
  for (const std::string& l : lines(a / "groundtruth_kitti.txt")) {
    T_gt.push_back(kittiPose(l));
    gt.push_back(T_gt.back().translation());
  }
  ASSERT_EQ(gt.size(), 120u);
  // The reset: one new world, starting with the camera at the identity, and loops from the new
  // world to the first lap.
  EXPECT_NE(stats.find("\"world_resets\": 1,"), std::string::npos) << stats;
  EXPECT_EQ(online[kResetFrame].substr(0, 8), "1.000000") << online[kResetFrame];
  int across = 0;
  for (std::size_t p = stats.find("\"query_frame\": "); p != std::string::npos;
       p = stats.find("\"query_frame\": ", p + 1)) {
    const std::size_t c_at = stats.find("\"candidate_frame\": ", p);
    if (std::stoi(stats.substr(p + 15)) >= kResetFrame &&
        std::stoi(stats.substr(c_at + 19)) < kResetFrame)
      ++across;
  }
  EXPECT_GE(across, 2) << stats;
  // In the new world (ground truth T_gt(reset)^-1 T_gt(i)): the optimised trajectory before the
  // reset has been brought in (online it is in the old world, tens of metres off), and after
  // it neither trajectory was moved by an old world's correction.
  const Eigen::Isometry3d W = T_gt[kResetFrame].inverse();
  auto rms = [&](const std::vector<std::string>& est, int from, int to) {
    double s = 0;
    for (int i = from; i < to; ++i)
      s += (kittiPose(est[static_cast<std::size_t>(i)]).translation() -
            (W * T_gt[static_cast<std::size_t>(i)]).translation())
               .squaredNorm();
    return std::sqrt(s / (to - from));
  };
  const double pre_online = rms(online, 0, kResetFrame), pre_opt = rms(optimised, 0, kResetFrame);
  const double post_online = rms(online, kResetFrame, 120), post_opt = rms(optimised, kResetFrame, 120);
  std::printf("in the new world, rms position error: before the reset online %.3f m, optimised "
              "%.3f m; after it online %.3f m, optimised %.3f m\n",
              pre_online, pre_opt, post_online, post_opt);
  EXPECT_GT(pre_online, 10.0);
  EXPECT_LT(pre_opt, 0.3);
  EXPECT_LT(post_online, 0.3);
  EXPECT_LT(post_opt, 0.3);
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
  // Re-placed during the flight too (map.replace_period_s): each time the whole map on
  // SVSLAM_MAP_TILE_OPTIMIZED, and empty tiles where the map moved away (the first lap moved
  // into the new world).
  const std::size_t rl = stats.find("\"replaced_live\": ");
  ASSERT_NE(rl, std::string::npos) << stats;
  EXPECT_GE(std::stoi(stats.substr(rl + 17)), 2) << stats;
  const std::size_t rt = stats.find("\"replaced_tiles_published\": ");
  ASSERT_NE(rt, std::string::npos) << stats;
  const int tiles = std::stoi(stats.substr(rt + 28));
  EXPECT_GE(tiles, 10) << stats;
  ASSERT_EQ(run("listen --url 'file://" + log.string() +
                    "?speed=0' --channel SVSLAM_MAP_TILE_OPTIMIZED",
                err),
            0)
      << err;
  const std::vector<std::string> msgs = lines(dir_ / "out.txt");
  EXPECT_EQ(static_cast<int>(msgs.size()), tiles);
  int empty = 0;
  for (const std::string& m : msgs) empty += m.find("\"valid_cells\": 0,") != std::string::npos;
  EXPECT_GE(empty, 1);
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

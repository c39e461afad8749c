// `svslam run` end to end through the executable: outputs, determinism, accuracy on real data
// (skipped with a message when ../shared/data is absent), and clear errors on bad input with
// nothing already written lost.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_helpers.hpp"
#include "drivers/files/trajectory_io.hpp"

namespace fs = std::filesystem;
using svslam::test::slurp;

namespace {

const std::string kKitti = std::string(SVSLAM_DATA_DIR) + "/kitti_odometry_seq_a";

int countLines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

class Run : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = svslam::test::freshTestDir("svslam_run_"); }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  int run(const std::string& args, std::string* err = nullptr) const {
    const int code = svslam::test::runSvslam("run " + args, path("stdout.txt"), path("stderr.txt"));
    if (err) *err = slurp(path("stderr.txt"));
    return code;
  }
  // A copy of the KITTI sequence's calib.txt and its first `frames` image pairs (by name) in
  // dir_/seq; returns that folder.
  fs::path copyKittiPrefix(int frames) const {
    const fs::path seq = dir_ / "seq";
    for (const char* side : {"image_l", "image_r"}) {
      fs::create_directories(seq / side);
      std::vector<fs::path> images;
      for (const auto& e : fs::directory_iterator(kKitti + "/" + side)) images.push_back(e.path());
      std::sort(images.begin(), images.end());
      for (int i = 0; i < frames; ++i)
        fs::copy_file(images[static_cast<std::size_t>(i)],
                      seq / side / images[static_cast<std::size_t>(i)].filename());
    }
    fs::copy_file(kKitti + "/calib.txt", seq / "calib.txt");
    return seq;
  }
  fs::path dir_;
};

bool haveKitti() { return fs::exists(kKitti + "/calib.txt"); }

}  // namespace

TEST_F(Run, KittiOutputsAreCompleteAndDeterministic) {
  if (!haveKitti()) GTEST_SKIP() << "no KITTI data at " << kKitti;
  ASSERT_EQ(run("--source kitti:" + kKitti + " --max-frames 6 --out " + path("a")), 0);
  ASSERT_EQ(run("--source kitti:" + kKitti + " --max-frames 6 --out " + path("b")), 0);
  for (const char* f : {"trajectory_kitti.txt", "trajectory_tum.txt", "stats.json"}) {
    const std::string a = slurp(path("a/") + f), b = slurp(path("b/") + f);
    ASSERT_FALSE(a.empty()) << f;
    if (std::string(f) != "stats.json") {
      EXPECT_EQ(a, b) << f << " differs between two runs";
    }
  }
  EXPECT_EQ(countLines(slurp(path("a/trajectory_kitti.txt"))), 6);
  EXPECT_EQ(countLines(slurp(path("a/trajectory_tum.txt"))), 6);
  const std::string stats = slurp(path("a/stats.json"));
  for (const char* key : {"\"frames\": 6", "\"frames_without_pose\"", "\"stage_ms\"", "\"p50_ms\"",
                          "\"p99_ms\"", "\"max_ms\"", "\"front_end\""})
    EXPECT_NE(stats.find(key), std::string::npos) << key << " missing in " << stats;
  // The first pose is the identity (KITTI convention).
  auto t = svslam::drivers::readTrajectory(path("a/trajectory_kitti.txt"));
  ASSERT_TRUE(t.isOk());
  EXPECT_TRUE(t->poses.front().isApprox(Eigen::Isometry3d::Identity()));
}

// The right camera fails mid-flight (the synthetic source blacks it out): every frame still has
// a finite pose, and stats.json says what happened.
TEST_F(Run, RightCameraLossIsFlownOnAndReported) {
  ASSERT_EQ(run("--source synthetic:width=320,height=240,frames=30,right_black_from=12,"
                "right_black_to=20 --out " + path("a")),
            0);
  const std::string stats = slurp(path("a/stats.json"));
  // Frames 12-19 black, stereo resumes at the third good frame (22): 10 mono frames.
  for (const char* key : {"\"frames_without_pose\": 0", "\"frames_monocular\": 10",
                          "\"right_camera_losses\": 1", "\"right_camera_flat_frames\": 8"})
    EXPECT_NE(stats.find(key), std::string::npos) << key << " missing in " << stats;
  auto t = svslam::drivers::readTrajectory(path("a/trajectory_kitti.txt"));
  ASSERT_TRUE(t.isOk());
  ASSERT_EQ(t->poses.size(), 30u);
  for (const auto& T : t->poses) EXPECT_TRUE(T.matrix().allFinite());
}

TEST_F(Run, MonoModeRunsFromTheLeftCameraAndSaysSo) {
  ASSERT_EQ(run("--mode mono --source synthetic:width=320,height=240,frames=12 --out " +
                path("m")),
            0);
  const std::string stats = slurp(path("m/stats.json"));
  for (const char* key : {"\"mode\": \"mono\"", "\"frames_without_pose\": 0",
                          "\"frames_monocular\": 12"})
    EXPECT_NE(stats.find(key), std::string::npos) << key << " missing in " << stats;
  auto t = svslam::drivers::readTrajectory(path("m/trajectory_kitti.txt"));
  ASSERT_TRUE(t.isOk());
  ASSERT_EQ(t->poses.size(), 12u);
  for (const auto& T : t->poses) EXPECT_TRUE(T.matrix().allFinite());
  std::string err;
  EXPECT_NE(run("--mode stereo --out " + path("o"), &err), 0);
  EXPECT_NE(err.find("mono"), std::string::npos) << err;  // the list of modes
}

TEST_F(Run, BadInputGivesAClearErrorAndNonZeroExit) {
  std::string err;
  EXPECT_NE(run("--source nowhere:x --out " + path("o"), &err), 0);
  EXPECT_NE(err.find("unknown source"), std::string::npos) << err;
  EXPECT_NE(run("--source kitti:/nonexistent/dir --out " + path("o"), &err), 0);
  EXPECT_NE(err.find("/nonexistent/dir"), std::string::npos) << err;
  std::ofstream(path("bad.yaml")) << "stereo_match: {min_zncc: 7}\n";
  EXPECT_NE(run("--config " + path("bad.yaml") + " --source kitti:" + kKitti, &err), 0);
  EXPECT_NE(err.find("stereo_match.min_zncc"), std::string::npos) << err;
  EXPECT_NE(run("--config " + path("missing.yaml"), &err), 0);
  EXPECT_NE(err.find("missing.yaml"), std::string::npos) << err;
  // A folder is not a configuration file (it used to run with the defaults).
  fs::create_directories(path("conf.d"));
  EXPECT_NE(run("--config " + path("conf.d") + " --source nowhere:x", &err), 0);
  EXPECT_NE(err.find(path("conf.d") + "' is a directory"), std::string::npos) << err;
  EXPECT_NE(run("--max-frames -3", &err), 0);
  EXPECT_NE(err.find("max-frames"), std::string::npos) << err;
}

TEST_F(Run, CorruptFrameKeepsWhatWasWritten) {
  if (!haveKitti()) GTEST_SKIP() << "no KITTI data at " << kKitti;
  // A copy of the first 5 frames with frame 3 of the left camera truncated.
  const fs::path seq = copyKittiPrefix(5);
  fs::resize_file(seq / "image_l" / "000003.png", 100);
  std::string err;
  EXPECT_EQ(run("--source kitti:" + seq.string() + " --out " + path("o"), &err), 1);
  EXPECT_NE(err.find("000003.png"), std::string::npos) << err;
  EXPECT_EQ(countLines(slurp(path("o/trajectory_kitti.txt"))), 3);  // frames 0..2 kept
  EXPECT_NE(slurp(path("o/stats.json")).find("\"error\""), std::string::npos);
}

TEST_F(Run, ReusedOutputFolderHoldsOnlyThisRunsFiles) {
  // An earlier run's files in the folder: those this run would write are removed at its start
  // (a vo run without the map writes no covariance, landmarks or map files); others stay.
  fs::create_directories(path("o"));
  for (const char* f :
       {"trajectory_kitti.txt", "pose_covariance.txt", "landmarks.ply", "stats.json",
        "stats.json.tmp", "dem.tif", "ortho.png", "groundtruth_dem.tif"})
    std::ofstream(path("o/") + f) << "stale\nstale\nstale\nstale\nstale\n";
  std::ofstream(path("o/notes.txt")) << "mine\n";
  std::ofstream(path("c.yaml")) << "dense_stereo: {enabled: false}\nmap: {enabled: false}\n";
  std::string err;
  ASSERT_EQ(run("--source synthetic:width=320,height=240,frames=3 --mode vo --config " +
                    path("c.yaml") + " --out " + path("o"),
                &err),
            0)
      << err;
  EXPECT_EQ(countLines(slurp(path("o/trajectory_kitti.txt"))), 3);
  EXPECT_NE(slurp(path("o/stats.json")).find("\"frames\": 3,"), std::string::npos);
  for (const char* f : {"pose_covariance.txt", "landmarks.ply", "stats.json.tmp", "dem.tif",
                        "ortho.png", "groundtruth_dem.tif"})
    EXPECT_FALSE(fs::exists(path("o/") + f)) << f << " of the earlier run is still there";
  EXPECT_EQ(slurp(path("o/notes.txt")), "mine\n");
}

TEST_F(Run, KittiFrameWithOneSideMissingIsSkippedAndCounted) {
  if (!haveKitti()) GTEST_SKIP() << "no KITTI data at " << kKitti;
  // The first 4 frames, the right image of frame 2 missing.
  const fs::path seq = copyKittiPrefix(4);
  fs::remove(seq / "image_r" / "000002.png");
  std::ofstream(path("c.yaml")) << "dense_stereo: {enabled: false}\nmap: {enabled: false}\n";
  std::string err;
  ASSERT_EQ(
      run("--source kitti:" + seq.string() + " --config " + path("c.yaml") + " --out " + path("o"),
          &err),
      0)
      << err;
  EXPECT_NE(err.find("1 frame(s) of the source skipped: 000002 (no right image)"),
            std::string::npos)
      << err;
  EXPECT_EQ(countLines(slurp(path("o/trajectory_kitti.txt"))), 3);
  const std::string stats = slurp(path("o/stats.json"));
  EXPECT_NE(stats.find("\"source_frames_skipped\": 1,"), std::string::npos) << stats;
}

// --loops replays a preloaded sequence in one run (scripts/soak.sh): every replay is published,
// indices and stamps run on, and latency.txt holds one line per published frame. Without
// --preload it is refused.
TEST_F(Run, LoopedReplayPublishesEveryReplayAndLogsLatency) {
  std::string err;
  const std::string src = " --source synthetic:width=160,height=120,frames=4,loop_frames=4";
  EXPECT_NE(run(src + " --loops 3 --out " + path("o"), &err), 0);
  EXPECT_NE(err.find("--preload"), std::string::npos) << err;
  EXPECT_NE(run(src + " --preload --loops 0 --out " + path("o"), &err), 0);
  EXPECT_NE(err.find("loops"), std::string::npos) << err;
  std::ofstream(path("log.yaml")) << "pipeline: {latency_log: true}\n";
  ASSERT_EQ(
      run(src + " --preload --loops 3 --config " + path("log.yaml") + " --out " + path("o"), &err),
      0)
      << err;
  EXPECT_EQ(countLines(slurp(path("o/trajectory_tum.txt"))), 12);
  const std::string latency = slurp(path("o/latency.txt"));
  EXPECT_EQ(countLines(latency), 12) << latency;
  std::istringstream in(latency);
  long long seq = -1, expected = 0;
  double ms = -1;
  while (in >> seq >> ms) {
    EXPECT_EQ(seq, expected++);
    EXPECT_GT(ms, 0.0);
  }
  EXPECT_EQ(expected, 12);
  // The TUM stamps increase across the wraps.
  std::istringstream tum(slurp(path("o/trajectory_tum.txt")));
  double t = 0, last_t = -1;
  std::string rest;
  while (tum >> t && std::getline(tum, rest)) {
    EXPECT_GT(t, last_t);
    last_t = t;
  }
}

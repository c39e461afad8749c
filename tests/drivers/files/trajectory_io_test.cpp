// Trajectory files: KITTI and TUM parsing, EuRoC T_BS, association, and errors naming the line.
#include "drivers/files/trajectory_io.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace svslam::drivers {
namespace {

class TrajectoryIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("svslam_traj_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  fs::path dir_;
};

TEST_F(TrajectoryIo, ReadsKittiAndTum) {
  auto k = readTrajectory(
      write("k.txt", "1 0 0 1 0 1 0 2 0 0 1 3\n# comment\n1 0 0 4 0 1 0 5 0 0 1 6\n"));
  ASSERT_TRUE(k.isOk()) << k.status().message();
  EXPECT_EQ(k->format, TrajectoryFormat::kKitti);
  ASSERT_EQ(k->poses.size(), 2u);
  EXPECT_TRUE(k->poses[1].translation().isApprox(Eigen::Vector3d(4, 5, 6)));
  EXPECT_TRUE(k->t_ns.empty());
  auto t = readTrajectory(write("t.txt",
                                "# t tx ty tz qx qy qz qw\n1.5 1 2 3 0 0 0 1\n1403636584763555584 "
                                "0 0 0 0 0 0.7071068 0.7071068\n"));
  ASSERT_TRUE(t.isOk()) << t.status().message();
  EXPECT_EQ(t->format, TrajectoryFormat::kTum);
  EXPECT_EQ(t->t_ns[0], 1500000000);
  EXPECT_EQ(t->t_ns[1], 1403636584763555584);          // large values are nanoseconds
  EXPECT_NEAR(t->poses[1].linear()(1, 0), 1.0, 1e-6);  // 90 deg about z
}

// TUM times in seconds with up to nine decimals (as svslam writes them) are read to the
// nanosecond: a double alone would be about 240 ns off at EuRoC's 1.4e9 s.
TEST_F(TrajectoryIo, TumSecondsAreReadToTheNanosecond) {
  auto t = readTrajectory(write("ns.txt",
                                "1403636584.763555765 0 0 0 0 0 0 1\n"
                                "-2.5 0 0 0 0 0 0 1\n"
                                "7 0 0 0 0 0 0 1\n"
                                "1.5e3 0 0 0 0 0 0 1\n"
                                "0.00000000200 0 0 0 0 0 0 1\n"));
  ASSERT_TRUE(t.isOk()) << t.status().message();
  ASSERT_EQ(t->t_ns.size(), 5u);
  EXPECT_EQ(t->t_ns[0], 1403636584763555765LL);
  EXPECT_EQ(t->t_ns[1], -2500000000LL);
  EXPECT_EQ(t->t_ns[2], 7000000000LL);
  EXPECT_EQ(t->t_ns[3], 1500000000000LL);  // exponent form: through the double
  EXPECT_EQ(t->t_ns[4], 2);                // eleven decimals: through the double, rounded
}

TEST_F(TrajectoryIo, ErrorsNameFileAndLine) {
  auto missing = readTrajectory((dir_ / "nope.txt").string());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  auto short_line = readTrajectory(write("a.txt", "1 0 0 1 0 1 0 2 0 0 1 3\n1 0 0\n"));
  ASSERT_FALSE(short_line.isOk());
  EXPECT_NE(short_line.status().message().find("a.txt:2"), std::string::npos)
      << short_line.status().message();
  auto word = readTrajectory(write("b.txt", "1 0 0 one 0 1 0 2 0 0 1 3\n"));
  EXPECT_FALSE(word.isOk());
  auto nan = readTrajectory(write("c.txt", "1 0 0 nan 0 1 0 2 0 0 1 3\n"));
  EXPECT_FALSE(nan.isOk());
  auto empty = readTrajectory(write("d.txt", "# nothing\n"));
  EXPECT_FALSE(empty.isOk());
  auto zero_q = readTrajectory(write("e.txt", "1 0 0 0 0 0 0 0\n"));
  EXPECT_FALSE(zero_q.isOk());
}

TEST_F(TrajectoryIo, RotationsMustBeRotations) {
  // Rounded to 7 digits: accepted (projected onto a rotation).
  auto rounded =
      readTrajectory(write("r.txt", "0.7071068 -0.7071068 0 0 0.7071068 0.7071068 0 0 0 0 1 0\n"));
  ASSERT_TRUE(rounded.isOk()) << rounded.status().message();
  auto expectError = [&](const std::string& name, const std::string& text,
                         const std::string& needle) {
    auto r = readTrajectory(write(name, text));
    ASSERT_FALSE(r.isOk()) << name;
    EXPECT_NE(r.status().message().find(needle), std::string::npos) << r.status().message();
  };
  expectError("scaled.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 0 0 2 0 0 0 0 2 0\n",
              "scaled.txt:2: the 3x3 part is not a rotation");
  expectError("sheared.txt", "1 0.1 0 0 0 1 0 0 0 0 1 0\n", "sheared.txt:1: the 3x3 part");
  expectError("mirror.txt", "-1 0 0 0 0 1 0 0 0 0 1 0\n", "det = -1");
  expectError("q.txt", "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 2\n",
              "q.txt:2: the quaternion is not a unit one (norm 2)");
  expectError("t.txt", "1e30 0 0 0 0 0 0 1\n", "t.txt:1: time stamp");
  expectError("t2.txt", "1e11 0 0 0 0 0 0 1\n", "out of range");
}

TEST_F(TrajectoryIo, AssociatesByIndexOrStamp) {
  TrajectoryFile a, b;
  for (int i = 0; i < 5; ++i) {
    a.poses.push_back(Eigen::Isometry3d::Identity());
    b.poses.push_back(Eigen::Isometry3d::Identity());
  }
  std::vector<Eigen::Isometry3d> g, e;
  EXPECT_TRUE(associateTrajectories(a, b, 0.01, g, e).isOk());
  EXPECT_EQ(g.size(), 5u);
  b.poses.pop_back();
  EXPECT_FALSE(associateTrajectories(a, b, 0.01, g, e).isOk());  // by index: counts differ
  a.format = b.format = TrajectoryFormat::kTum;
  a.t_ns = {0, 100000000, 200000000, 300000000, 400000000};
  b.t_ns = {5000000, 205000000, 290000000, 1000000000};
  ASSERT_TRUE(associateTrajectories(a, b, 0.02, g, e).isOk());
  EXPECT_EQ(g.size(), 3u);  // the 1 s stamp has no ground truth within 20 ms
}

TEST_F(TrajectoryIo, EurocTbs) {
  const std::string data =
      std::string(SVSLAM_DATA_DIR) + "/euroc_mh01_first320/mav0/cam0/sensor.yaml";
  if (!fs::exists(data)) GTEST_SKIP() << "shared data absent: " << data;
  auto T = readEurocTbs(data);
  ASSERT_TRUE(T.isOk()) << T.status().message();
  EXPECT_NEAR(T->linear().determinant(), 1.0, 1e-6);
  EXPECT_NEAR(T->translation().x(), -0.0216401454975, 1e-12);
  EXPECT_FALSE(readEurocTbs(write("s.yaml", "T_BS:\n  data: [1, 2, 3]\n")).isOk());
}

}  // namespace
}  // namespace svslam::drivers

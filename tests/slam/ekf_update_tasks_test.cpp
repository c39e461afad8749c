// The EKF update split into row pieces on an executor gives the same bits as on one thread, in
// the Joseph and the optimal-gain forms, for any number of pieces and any order of execution.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "motion/visual_motion.hpp"
#include "slam/ekf_slam.hpp"
#include "slam/pose_jacobians.hpp"

#include "../core/spawning_executor.hpp"

namespace svslam {
namespace {

using test_support::SpawningExecutor;

struct Outcome {
  Eigen::MatrixXd P;
  Eigen::Isometry3d T;
};

Outcome runFilter(bool joseph, int tasks, Executor* executor) {
  EkfSlamParams params;
  params.max_landmarks = 300;  // 250 below: rows enough to split into pieces
  params.max_batch_observations = 64;
  params.joseph_form = joseph;
  params.max_update_tasks = tasks;
  EkfSlam ekf(params);
  Matrix6d P0 = Matrix6d::Identity() * 1e-4;
  EXPECT_TRUE(ekf.reset(Eigen::Isometry3d::Identity(), P0).isOk());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(-10, 10), z(5, 30), noise(-0.01, 0.01);
  for (int i = 0; i < 250; ++i) {
    const Eigen::Vector3d p(x(rng), 0.5 * x(rng), z(rng));
    const Eigen::Vector3d s(0.01 * p.z(), 0.01 * p.z(), 0.002 * p.z() * p.z());
    EXPECT_TRUE(ekf.addLandmark(p, s.cwiseAbs2().asDiagonal()).isOk());
  }
  Eigen::Isometry3d u = Eigen::Isometry3d::Identity();
  u.translation() = Eigen::Vector3d(0.02, 0, -0.1);
  Matrix6d R_u = Matrix6d::Identity() * 1e-5;
  std::vector<LandmarkObservation> obs;
  std::vector<ObservationResult> res;
  for (int frame = 0; frame < 4; ++frame) {
    EXPECT_TRUE(ekf.predict(u, R_u).isOk());
    obs.clear();
    for (int j = 0; j < 30; ++j) {
      const int id = ekf.landmarkIds()[static_cast<std::size_t>((frame * 37 + j * 7) % 250)];
      Eigen::Vector3d m;
      Eigen::Matrix3d C;
      EXPECT_TRUE(ekf.landmark(id, m, C).isOk());
      const Eigen::Vector3d zc = observeLandmark(ekf.pose(), m);
      obs.push_back({id, zc + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)),
                     Eigen::Vector3d(1e-4, 1e-4, 1e-3).asDiagonal()});
    }
    EXPECT_TRUE(ekf.update(obs, res, executor).isOk());
  }
  return {ekf.covariance(), ekf.pose()};
}

bool sameBits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) ==
             0;
}

TEST(EkfUpdateTasks, RowPiecesOnAnExecutorGiveTheSameBits) {
  for (bool joseph : {true, false}) {
    const Outcome one = runFilter(joseph, 1, nullptr);
    for (int tasks : {2, 3, 5}) {
      SpawningExecutor ex(tasks);
      const Outcome many = runFilter(joseph, tasks, &ex);
      EXPECT_TRUE(sameBits(one.P, many.P)) << (joseph ? "joseph" : "optimal gain") << ", " << tasks;
      EXPECT_TRUE(sameBits(one.T.matrix(), many.T.matrix()));
    }
  }
}

TEST(EkfUpdateTasks, TaskCountOutsideItsRangeIsRejected) {
  EkfSlamParams p;
  p.max_update_tasks = 0;
  EXPECT_FALSE(p.validate().isOk());
  p.max_update_tasks = 17;
  EXPECT_FALSE(p.validate().isOk());
}

}  // namespace
}  // namespace svslam

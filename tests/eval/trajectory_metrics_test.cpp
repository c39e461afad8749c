// Trajectory metrics against cases with known answers: Umeyama recovers a rigid transform,
// a perfect estimate scores zero, a 1 % scale error gives 1 % drift on a straight path, a
// constant yaw-rate error gives the expected rotation drift.
#include "eval/trajectory_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace svslam {
namespace {

// A wavy path along z (camera forward), 1 m per frame, with gentle yaw.
std::vector<Eigen::Isometry3d> path(int n, double yaw_per_frame = 0.0) {
  std::vector<Eigen::Isometry3d> out;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < n; ++i) {
    out.push_back(T);
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    step.translation() = Eigen::Vector3d(0.05 * std::sin(0.1 * i), 0.0, 1.0);
    step.linear() = Eigen::AngleAxisd(yaw_per_frame, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T = T * step;
  }
  return out;
}

TEST(TrajectoryMetrics, UmeyamaRecoversRigidTransform) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 5);
  std::vector<Eigen::Vector3d> a, b;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(4, -2, 9);
  for (int i = 0; i < 50; ++i) {
    a.emplace_back(n(rng), n(rng), n(rng));
    b.push_back(T * a.back());
  }
  const Eigen::Isometry3d R = umeyamaSe3(a, b);
  EXPECT_TRUE(R.matrix().isApprox(T.matrix(), 1e-9));
}

TEST(TrajectoryMetrics, PerfectEstimateInAnotherFrameScoresZero) {
  const auto gt = path(200, 0.01);
  Eigen::Isometry3d W = Eigen::Isometry3d::Identity();
  W.linear() = Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  W.translation() = Eigen::Vector3d(10, 20, 30);
  std::vector<Eigen::Isometry3d> est;
  for (const auto& T : gt) est.push_back(W * T);
  TrajectoryEvalParams p;
  p.segment_lengths_m = {10, 50};
  for (auto align : {TrajectoryAlignment::kSe3, TrajectoryAlignment::kNone}) {
    p.align = align;
    auto m = evaluateTrajectory(gt, est, p);
    ASSERT_TRUE(m.isOk());
    EXPECT_NEAR(m->t_err_pct, 0, 1e-9);
    EXPECT_NEAR(m->r_err_deg_per_m, 0, 1e-9);
    EXPECT_NEAR(m->ate_rmse_m, 0, 1e-6);
    EXPECT_NEAR(m->final_att_err_deg, 0, 1e-6);
    EXPECT_NEAR(m->rpe_trans_rmse_m, 0, 1e-9);
  }
}

TEST(TrajectoryMetrics, ScaleErrorGivesProportionalDrift) {
  const auto gt = path(300);
  std::vector<Eigen::Isometry3d> est = gt;
  for (auto& T : est) T.translation() *= 1.01;
  TrajectoryEvalParams p;
  p.segment_lengths_m = {20, 100};
  p.step_frames = 1;
  auto m = evaluateTrajectory(gt, est, p);
  ASSERT_TRUE(m.isOk());
  EXPECT_NEAR(m->t_err_pct, 1.0, 0.01);
  EXPECT_NEAR(m->r_err_deg_per_m, 0.0, 1e-9);
  EXPECT_NEAR(m->path_length_m, 299.0, 0.5);
  ASSERT_EQ(m->segments.size(), 2u);
  EXPECT_GT(m->segments[1].count, 100);
}

TEST(TrajectoryMetrics, YawRateErrorGivesRotationDrift) {
  // 0.001 rad of extra yaw per 1 m frame: rotation drift = 0.001 rad/m = 0.0573 deg/m.
  const auto gt = path(200, 0.0);
  const auto est = path(200, 0.001);
  TrajectoryEvalParams p;
  p.segment_lengths_m = {50};
  auto m = evaluateTrajectory(gt, est, p);
  ASSERT_TRUE(m.isOk());
  EXPECT_NEAR(m->r_err_deg_per_m, 0.001 * 180 / M_PI, 1e-3);
  EXPECT_GT(m->final_pos_err_m, 1.0);
}

TEST(TrajectoryMetrics, RejectsBadInput) {
  auto gt = path(10);
  TrajectoryEvalParams p;
  EXPECT_FALSE(evaluateTrajectory(gt, path(9), p).isOk());
  EXPECT_FALSE(evaluateTrajectory(path(2), path(2), p).isOk());
  auto bad = gt;
  bad[3].translation().x() = std::nan("");
  EXPECT_FALSE(evaluateTrajectory(gt, bad, p).isOk());
  p.segment_lengths_m = {-1};
  EXPECT_FALSE(evaluateTrajectory(gt, gt, p).isOk());
}

}  // namespace
}  // namespace svslam

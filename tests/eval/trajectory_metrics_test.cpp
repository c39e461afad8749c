// Trajectory metrics against cases with known answers: Umeyama recovers a rigid transform,
// a perfect estimate scores zero, a 1 % scale error gives 1 % drift on a straight path, a
// constant yaw-rate error gives the expected rotation drift.
#include "eval/trajectory_metrics.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
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

TEST(TrajectoryMetrics, UmeyamaSim3RecoversSimilarity) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 5);
  std::vector<Eigen::Vector3d> a, b;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(-1.1, Eigen::Vector3d(3, -1, 2).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(-3, 7, 1);
  const double s = 2.5;
  for (int i = 0; i < 50; ++i) {
    a.emplace_back(n(rng), n(rng), n(rng));
    b.push_back(s * (R * a.back()) + t);
  }
  double scale = 0;
  const Eigen::Isometry3d T = umeyamaSim3(a, b, scale);
  EXPECT_NEAR(scale, s, 1e-9);
  EXPECT_TRUE(T.linear().isApprox(R, 1e-9));
  EXPECT_TRUE(T.translation().isApprox(t, 1e-9));
}

// An estimate at 0.6 of the true scale (monocular): after Sim(3) it scores zero, after SE(3)
// it does not.
TEST(TrajectoryMetrics, Sim3AlignmentRemovesAGlobalScale) {
  const auto gt = path(60, 0.02);
  std::vector<Eigen::Isometry3d> est;
  Eigen::Isometry3d W = Eigen::Isometry3d::Identity();
  W.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  W.translation() = Eigen::Vector3d(1, 2, 3);
  for (const auto& g : gt) {
    Eigen::Isometry3d e = g;
    e.translation() *= 0.6;
    est.push_back(W * e);
  }
  TrajectoryEvalParams p;
  p.segment_lengths_m = {10};
  p.align = TrajectoryAlignment::kSim3;
  auto m = evaluateTrajectory(gt, est, p);
  ASSERT_TRUE(m.isOk());
  EXPECT_NEAR(m->ate_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(m->align_scale, 1.0 / 0.6, 1e-9);
  p.align = TrajectoryAlignment::kSe3;
  auto r = evaluateTrajectory(gt, est, p);
  ASSERT_TRUE(r.isOk());
  EXPECT_GT(r->ate_rmse_m, 1.0);
  EXPECT_EQ(r->align_scale, 1.0);
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

TEST(TrajectoryMetrics, RotationAboutTheStartIsSeparatedFromTheShapeError) {
  // A loop-like path; the estimate, in another world frame, turns by Q0^T about its first camera
  // centre right after the first frame (an early attitude error every later pose inherits), then
  // a known shape error at the last frame.
  std::vector<Eigen::Isometry3d> gt;
  for (int i = 0; i < 120; ++i) {
    const double a = 2 * M_PI * i / 120.0;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(40 * std::sin(a), 40 * (1 - std::cos(a)), 0.3 * std::sin(3 * a));
    gt.push_back(T);
  }
  Eigen::Isometry3d world = Eigen::Isometry3d::Identity();  // the estimate's own world frame
  world.linear() = Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  world.translation() = Eigen::Vector3d(3, 1, -7);
  const Eigen::Matrix3d Q0 =
      Eigen::AngleAxisd(0.002, Eigen::Vector3d(0.6, 0.8, 0).normalized()).toRotationMatrix();
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();  // about the first camera centre
  turn.linear() = Q0.transpose();
  ASSERT_TRUE(gt[0].isApprox(Eigen::Isometry3d::Identity()));
  std::vector<Eigen::Isometry3d> est;
  for (std::size_t i = 0; i < gt.size(); ++i) est.push_back(i == 0 ? world : world * turn * gt[i]);
  TrajectoryEvalParams p;
  p.segment_lengths_m = {50};
  p.align = TrajectoryAlignment::kNone;
  auto m = evaluateTrajectory(gt, est, p);
  ASSERT_TRUE(m.isOk());
  EXPECT_GT(m->ate_rmse_m, 0.05);  // the turn alone moves the far side by 80 m * 2 mrad
  EXPECT_NEAR(m->start_rotation_deg, 0.002 * 180 / M_PI, 1e-9);
  // Axis in the first camera frame: gt[0] is the identity here.
  EXPECT_NEAR(std::abs(m->start_rotation_axis.dot(Eigen::Vector3d(0.6, 0.8, 0))), 1.0, 1e-6);
  EXPECT_LT(m->ate_after_start_rotation_m, 1e-9);
  EXPECT_LT(m->final_pos_err_after_start_rotation_m, 1e-9);

  // A shape error (the last position 5 cm off) stays after the rotation is removed.
  est.back().translation() += world.linear() * Eigen::Vector3d(0, 0, 0.05);
  m = evaluateTrajectory(gt, est, p);
  ASSERT_TRUE(m.isOk());
  EXPECT_NEAR(m->final_pos_err_after_start_rotation_m, 0.05, 2e-3);
  EXPECT_NEAR(m->start_rotation_deg, 0.002 * 180 / M_PI, 2e-3);
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

// NEES against covariances the errors were drawn from: about 6 on average, and ~95 % of frames
// within 2 sigma per position axis (0.954^3 ~ 87 % for all three at once).
TEST(Nees, MatchesTheSamplingCovariance) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::vector<Eigen::Isometry3d> gt, est;
  std::vector<Eigen::Matrix<double, 6, 6>> cov;
  for (int i = 0; i < 4000; ++i) {
    Eigen::Isometry3d G = Eigen::Isometry3d::Identity();
    G.translate(Eigen::Vector3d(0.1 * i, 0.02 * i, 0));
    G.rotate(Eigen::AngleAxisd(0.01 * i, Eigen::Vector3d::UnitZ()));
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random() * 0.1;
    Eigen::Matrix<double, 6, 6> P = A * A.transpose() + 1e-3 * Eigen::Matrix<double, 6, 6>::Identity();
    if (i == 0) P.setZero();  // the first frame has no uncertainty and is skipped
    Eigen::Matrix<double, 6, 1> e = Eigen::Matrix<double, 6, 1>::Zero();
    if (i > 0) {
      Eigen::Matrix<double, 6, 1> w;
      for (int k = 0; k < 6; ++k) w(k) = n01(rng);
      e = Eigen::LLT<Eigen::Matrix<double, 6, 6>>(P).matrixL() * w;
    }
    // e = [log(R_gt R_est^T), t_gt - t_est]  ->  R_est = exp(-e_rot) R_gt, t_est = t_gt - e_t.
    Eigen::Isometry3d E = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d r = e.head<3>();
    E.linear() = (r.norm() > 0 ? Eigen::AngleAxisd(-r.norm(), r.normalized()).toRotationMatrix()
                               : Eigen::Matrix3d::Identity()) *
                 G.linear();
    E.translation() = G.translation() - e.tail<3>();
    gt.push_back(G);
    est.push_back(E);
    cov.push_back(P);
  }
  auto r = svslam::evaluateNees(gt, est, cov);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->frames, 3999);
  EXPECT_NEAR(r->mean_nees, 6.0, 0.3);
  EXPECT_NEAR(r->mean_nees_position, 3.0, 0.2);
  EXPECT_NEAR(r->position_within_2sigma_pct, 100 * std::pow(0.9545, 3), 2.5);
  // Twice the errors: NEES four times larger.
  for (std::size_t i = 1; i < est.size(); ++i) cov[i] /= 4.0;
  auto r4 = svslam::evaluateNees(gt, est, cov);
  ASSERT_TRUE(r4.isOk());
  EXPECT_NEAR(r4->mean_nees, 24.0, 1.5);
  cov.pop_back();
  EXPECT_FALSE(svslam::evaluateNees(gt, est, cov).isOk());
}

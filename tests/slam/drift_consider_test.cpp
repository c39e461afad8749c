// The drift consider covariance (slam/drift_consider.hpp) against its definition: trajectories
// whose every step is turned by a drawn constant rotation rate b (rad per metre of the step)
// have the sample covariance of the model, the error taken as the evaluation takes it
// (log(R^ R^T), t^ - t); on a straight path the attitude's standard deviation is sigma times
// the distance whatever the frame rate; a new origin restarts the model.
#include "slam/drift_consider.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "consider_test_support.hpp"

namespace svslam {
namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

using consider_test::logRotation;
using consider_test::pose;

// A drive with turns and climbs: 40 steps of about 1.2 m, each turning by up to 3 degrees.
std::vector<Isometry3d> drive() {
  std::vector<Isometry3d> steps;
  for (int k = 0; k < 40; ++k) {
    const double s = std::sin(0.3 * k), c = std::cos(0.2 * k);
    steps.push_back(pose({0.01 * c, 0.05 * s, 0.02 * s * c}, {0.1 * s, 0.05 * c, 1.2 + 0.2 * s}));
  }
  return steps;
}

TEST(DriftConsider, FirstOrderCovarianceMatchesDrawnDriftRates) {
  DriftConsiderParams p;
  p.sigma_rotation_rad_per_m = 0.5e-3;
  DriftConsider consider(p);
  ASSERT_TRUE(consider.initStatus());
  const Isometry3d T_wo = pose({0.1, -0.3, 0.2}, {5, -2, 30});
  const std::vector<Isometry3d> steps = drive();
  std::vector<Isometry3d> T_oc{Isometry3d::Identity()};
  for (const Isometry3d& dT : steps) T_oc.push_back(T_oc.back() * dT);
  std::vector<Matrix6> model;
  for (const Isometry3d& T : T_oc) {
    Matrix6 cov;
    ASSERT_TRUE(consider.process(T_wo, T_wo * T, cov));
    model.push_back(cov);
  }
  EXPECT_EQ(model.front().cwiseAbs().maxCoeff(), 0.0);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  const int draws = 20000;
  const std::vector<std::size_t> checked{10, 25, 40};
  std::vector<Matrix6> sample(checked.size(), Matrix6::Zero());
  for (int i = 0; i < draws; ++i) {
    const Vector3d b = p.sigma_rotation_rad_per_m * Vector3d(n(rng), n(rng), n(rng));
    Isometry3d T_hat = Isometry3d::Identity();
    std::size_t next = 0;
    for (std::size_t k = 1; k < T_oc.size(); ++k) {
      const Isometry3d& dT = steps[k - 1];
      Isometry3d dT_hat = dT;
      dT_hat.linear() = pose(dT.translation().norm() * b, Vector3d::Zero()).linear() * dT.linear();
      T_hat = T_hat * dT_hat;
      if (next < checked.size() && k == checked[next]) {
        const Isometry3d T_wc = T_wo * T_oc[k], T_wc_hat = T_wo * T_hat;
        Vector6 e;
        e.head<3>() = logRotation(T_wc_hat.linear() * T_wc.linear().transpose());
        e.tail<3>() = T_wc_hat.translation() - T_wc.translation();
        sample[next++] += e * e.transpose();
      }
    }
  }
  for (std::size_t j = 0; j < checked.size(); ++j) {
    sample[j] /= draws;
    const Matrix6& cov = model[checked[j]];
    // Sampling error of a variance with 20000 draws: about 1 %; the linearisation's is smaller
    // (attitude errors of about 25 mrad at the end).
    const double scale = cov.diagonal().maxCoeff();
    ASSERT_GT(scale, 0);
    EXPECT_LT((sample[j] - cov).cwiseAbs().maxCoeff() / scale, 0.04)
        << "step " << checked[j] << "\nmodel\n" << cov << "\nsample\n" << sample[j];
  }
}

TEST(DriftConsider, StraightPathGrowsWithTheDistanceNotTheFrameCount) {
  DriftConsiderParams p;
  p.sigma_rotation_rad_per_m = 1e-3;
  // 100 m along the optical axis in 100 steps and in 25.
  Matrix6 fine, coarse;
  for (auto [steps, out] : {std::pair<int, Matrix6*>{100, &fine}, {25, &coarse}}) {
    DriftConsider consider(p);
    for (int k = 0; k <= steps; ++k)
      ASSERT_TRUE(consider.process(Isometry3d::Identity(),
                                   pose(Vector3d::Zero(), {0, 0, 100.0 * k / steps}), *out));
  }
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(std::sqrt(fine(a, a)), 0.1, 1e-12);  // sigma x 100 m about every axis
    EXPECT_NEAR(std::sqrt(coarse(a, a)), 0.1, 1e-12);
  }
  // Sideways: a rate about x or y bends the path, sum over steps of phi x step -> sigma L^2 / 2
  // in the limit of small steps (discretely sigma d^2 n (n - 1) / 2); nothing along it.
  EXPECT_NEAR(std::sqrt(fine(3, 3)), 1e-3 * 100 * 99 / 2, 1e-9);
  EXPECT_NEAR(std::sqrt(coarse(4, 4)), 1e-3 * 16 * 25 * 24 / 2, 1e-9);
  EXPECT_LT(fine(5, 5), 1e-20);
}

TEST(DriftConsider, NewOriginRestartsAndInactiveIsZero) {
  DriftConsiderParams p;
  p.sigma_rotation_rad_per_m = 1e-3;
  DriftConsider consider(p);
  Matrix6 cov;
  ASSERT_TRUE(consider.process(Isometry3d::Identity(), Isometry3d::Identity(), cov));
  ASSERT_TRUE(consider.process(Isometry3d::Identity(), pose({0, 0.1, 0}, {0, 0, 10}), cov));
  EXPECT_GT(cov(0, 0), 0.0);
  const Isometry3d T_wo = pose({0, 0.1, 0}, {0, 0, 10});
  ASSERT_TRUE(consider.process(T_wo, T_wo, cov));
  EXPECT_EQ(cov.cwiseAbs().maxCoeff(), 0.0);
  ASSERT_TRUE(consider.process(T_wo, T_wo * pose(Vector3d::Zero(), {0, 0, 5}), cov));
  EXPECT_NEAR(std::sqrt(cov(1, 1)), 5e-3, 1e-12);
  DriftConsider off(DriftConsiderParams{});
  ASSERT_TRUE(off.process(Isometry3d::Identity(), Isometry3d::Identity(), cov));
  ASSERT_TRUE(off.process(Isometry3d::Identity(), pose({0.3, 0, 0}, {10, 0, 5}), cov));
  EXPECT_EQ(cov.cwiseAbs().maxCoeff(), 0.0);
}

TEST(DriftConsider, RejectsBadParametersAndPoses) {
  DriftConsiderParams p;
  p.sigma_rotation_rad_per_m = std::nan("");
  EXPECT_FALSE(DriftConsider(p).initStatus());
  p.sigma_rotation_rad_per_m = -1e-4;
  EXPECT_FALSE(DriftConsider(p).initStatus());
  p.sigma_rotation_rad_per_m = 1.0;
  EXPECT_FALSE(DriftConsider(p).initStatus());
  p.sigma_rotation_rad_per_m = 1e-3;
  DriftConsider consider(p);
  Isometry3d bad = Isometry3d::Identity();
  bad.translation().x() = std::nan("");
  Matrix6 cov = Matrix6::Ones();
  const Status s = consider.process(Isometry3d::Identity(), bad, cov);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("non-finite"), std::string::npos);
  EXPECT_EQ(cov.cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace svslam

// Relative-pose residual and the composition / inversion Jacobians of loop/relative_pose.hpp
// against numerical differentiation in the left-perturbation convention (boxPlus).
#include "loop/relative_pose.hpp"

#include <gtest/gtest.h>

#include <random>

#include "motion/visual_motion.hpp"

namespace svslam {
namespace {

Eigen::Isometry3d pose(const Eigen::Vector3d& w, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = expSO3(w);
  T.translation() = t;
  return T;
}

Eigen::Isometry3d randomPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  return pose(Eigen::Vector3d(u(rng), u(rng), u(rng)), 5 * Eigen::Vector3d(u(rng), u(rng), u(rng)));
}

TEST(RelativePose, ResidualIsZeroAtTruth) {
  std::mt19937 rng(3);
  for (int i = 0; i < 10; ++i) {
    const Eigen::Isometry3d T_world_a = randomPose(rng), T_world_b = randomPose(rng);
    const Eigen::Isometry3d Z = T_world_a.inverse() * T_world_b;
    EXPECT_LT(relativePoseResidual(T_world_a, T_world_b, Z).norm(), 1e-12);
  }
}

// Perturbing the measurement's truth by d (Z = boxPlus(Zhat, -d)) gives r = d exactly for the
// translation and to first order for the rotation; perturbing T_world_b on the left in frame a
// moves r by the same d: the sign convention of r = boxMinus(Zhat, Z).
TEST(RelativePose, ResidualFollowsTheLeftPerturbationConvention) {
  std::mt19937 rng(4);
  const Eigen::Isometry3d T_world_a = randomPose(rng), T_world_b = randomPose(rng);
  const Eigen::Isometry3d Zhat = T_world_a.inverse() * T_world_b;
  Vector6d d;
  d << 1e-3, -2e-3, 0.5e-3, 0.01, -0.02, 0.03;
  const Vector6d r = relativePoseResidual(T_world_a, T_world_b, boxPlus(Zhat, -d));
  EXPECT_LT((r - d).norm(), 1e-8);
  // Zhat' = boxPlus(Zhat, d) <=> T_world_b' = T_world_a boxPlus(Zhat, d).
  const Eigen::Isometry3d T_world_b2 = T_world_a * boxPlus(Zhat, d);
  EXPECT_LT((relativePoseResidual(T_world_a, T_world_b2, Zhat) - d).norm(), 1e-12);
  // Finite differences of r with respect to the measurement: dr/dZ = -I at the truth.
  for (int k = 0; k < 6; ++k) {
    const double h = 1e-6;
    const Vector6d e = Vector6d::Unit(k) * h;
    const Vector6d num = (relativePoseResidual(T_world_a, T_world_b, boxPlus(Zhat, e)) -
                          relativePoseResidual(T_world_a, T_world_b, boxPlus(Zhat, -e))) /
                         (2 * h);
    EXPECT_LT((num + Vector6d::Unit(k)).norm(), 1e-6) << k;
  }
}

TEST(RelativePose, InverseJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Isometry3d T = randomPose(rng);
    const Matrix6d J = inverseJacobian(T);
    const Eigen::Isometry3d Ti = T.inverse();
    for (int k = 0; k < 6; ++k) {
      const double h = 1e-6;
      const Vector6d e = Vector6d::Unit(k) * h;
      const Vector6d num =
          (boxMinus(boxPlus(T, e).inverse(), Ti) - boxMinus(boxPlus(T, -e).inverse(), Ti)) /
          (2 * h);
      EXPECT_LT((num - J.col(k)).norm(), 1e-6) << trial << " " << k;
    }
  }
}

TEST(RelativePose, ProductJacobiansMatchFiniteDifferences) {
  std::mt19937 rng(6);
  std::vector<Eigen::Isometry3d> factors;
  for (int i = 0; i < 4; ++i) factors.push_back(randomPose(rng));
  std::vector<Matrix6d> A;
  const Eigen::Isometry3d F = productJacobians(factors, A);
  ASSERT_EQ(A.size(), 4u);
  EXPECT_LT((F.matrix() - (factors[0] * factors[1] * factors[2] * factors[3]).matrix()).norm(),
            1e-12);
  auto product = [](const std::vector<Eigen::Isometry3d>& f) {
    Eigen::Isometry3d P = Eigen::Isometry3d::Identity();
    for (const auto& T : f) P = P * T;
    return P;
  };
  for (int f = 0; f < 4; ++f) {
    for (int k = 0; k < 6; ++k) {
      const double h = 1e-6;
      auto plus = factors, minus = factors;
      plus[f] = boxPlus(factors[f], Vector6d::Unit(k) * h);
      minus[f] = boxPlus(factors[f], -Vector6d::Unit(k) * h);
      const Vector6d num = (boxMinus(product(plus), F) - boxMinus(product(minus), F)) / (2 * h);
      EXPECT_LT((num - A[f].col(k)).norm(), 1e-5) << f << " " << k;
    }
  }
}

TEST(RelativePose, CovarianceAndPoseChecks) {
  EXPECT_TRUE(isValidCovariance(Matrix6d::Identity()));
  Matrix6d C = Matrix6d::Identity();
  C(0, 0) = -1;
  EXPECT_FALSE(isValidCovariance(C));
  C = Matrix6d::Identity();
  C(1, 2) = 0.5;  // not symmetric
  EXPECT_FALSE(isValidCovariance(C));
  C = Matrix6d::Identity();
  C(3, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(isValidCovariance(C));
  EXPECT_FALSE(isValidCovariance(Matrix6d::Zero()));
  EXPECT_TRUE(isValidPose(Eigen::Isometry3d::Identity()));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().x() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(isValidPose(T));
  T = Eigen::Isometry3d::Identity();
  T.linear() *= 2;
  EXPECT_FALSE(isValidPose(T));
}

}  // namespace
}  // namespace svslam

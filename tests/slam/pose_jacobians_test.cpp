// Analytic Jacobians of the pose composition, observation and landmark initialisation
// (slam/pose_jacobians.hpp) against central numerical differences.
#include "slam/pose_jacobians.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "ekf_test_support.hpp"

namespace svslam {
namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using ekf_test::numericJacobian;
using ekf_test::pose;

// The camera-frame covariance of LCM's pose_t: the right-multiplied error xi of a pose perturbed
// in the filter's convention, xi = [log(R_hat^T R), R_hat^T (t - t_hat)], differentiated
// numerically, is B^T d; the covariance is that map applied to P.
TEST(PoseJacobians, CameraFrameCovarianceIsTheRightMultipliedError) {
  const Isometry3d T_hat = pose({0.6, -1.1, 0.4}, {3, -2, 7});
  const auto J = numericJacobian<6, 6>([&](const Vector6d& d) {
    const Isometry3d T = boxPlus(T_hat, d);
    const Eigen::AngleAxisd aa(T_hat.linear().transpose() * T.linear());
    Vector6d xi;
    xi.head<3>() = aa.angle() * aa.axis();
    xi.tail<3>() = T_hat.linear().transpose() * (T.translation() - T_hat.translation());
    return xi;
  });
  Matrix6d A = Matrix6d::Random();
  const Matrix6d P = A * A.transpose() + Matrix6d::Identity();
  const Matrix6d expected = J * P * J.transpose();
  EXPECT_LT((cameraFrameCovariance(T_hat, P) - expected).cwiseAbs().maxCoeff(), 1e-7);
  // Invariants: the same trace per block (a rotation of each block), the identity pose keeps it.
  const Matrix6d C = cameraFrameCovariance(T_hat, P);
  const double c_rot = C.topLeftCorner<3, 3>().trace(), p_rot = P.topLeftCorner<3, 3>().trace();
  const double c_pos = C.bottomRightCorner<3, 3>().trace();
  const double p_pos = P.bottomRightCorner<3, 3>().trace();
  EXPECT_NEAR(c_rot, p_rot, 1e-12);
  EXPECT_NEAR(c_pos, p_pos, 1e-12);
  EXPECT_LT((cameraFrameCovariance(Isometry3d::Identity(), P) - P).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(PoseJacobians, PredictionMatchesNumericalDifferentiation) {
  const Isometry3d T = pose({0.3, -0.7, 0.2}, {4, -1, 2}),
                   u = pose({0.05, 0.02, -0.1}, {0.5, 0.1, 1.3});
  Matrix6d F_x, F_u;
  predictionJacobians(T, u, F_x, F_u);
  const Isometry3d T_new = predictPose(T, u);
  const auto nx = numericJacobian<6, 6>(
      [&](const Vector6d& d) { return Vector6d(boxMinus(predictPose(boxPlus(T, d), u), T_new)); });
  const auto nu = numericJacobian<6, 6>(
      [&](const Vector6d& d) { return Vector6d(boxMinus(predictPose(T, boxPlus(u, d)), T_new)); });
  EXPECT_LT((F_x - nx).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((F_u - nu).cwiseAbs().maxCoeff(), 1e-7);
}

TEST(PoseJacobians, ObservationAndInitialisationMatchNumericalDifferentiation) {
  const Isometry3d T = pose({-0.4, 0.9, 0.1}, {1, 2, -3});
  const Vector3d m(5, -2, 12), z(0.7, -0.3, 8);
  Matrix36d H_p, G_x;
  Matrix3d H_m, G_z;
  observationJacobians(T, m, H_p, H_m);
  initJacobians(T, z, G_x, G_z);
  const auto nHp = numericJacobian<3, 6>(
      [&](const Vector6d& d) { return Vector3d(observeLandmark(boxPlus(T, d), m)); });
  const auto nHm =
      numericJacobian<3, 3>([&](const Vector3d& d) { return Vector3d(observeLandmark(T, m + d)); });
  const auto nGx = numericJacobian<3, 6>(
      [&](const Vector6d& d) { return Vector3d(initLandmark(boxPlus(T, d), z)); });
  const auto nGz =
      numericJacobian<3, 3>([&](const Vector3d& d) { return Vector3d(initLandmark(T, z + d)); });
  EXPECT_LT((H_p - nHp).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((H_m - nHm).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((G_x - nGx).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((G_z - nGz).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((observeLandmark(T, initLandmark(T, z)) - z).norm(), 1e-12);
}

}  // namespace
}  // namespace svslam

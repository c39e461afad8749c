// The calibration consider covariance (slam/calibration_consider.hpp) against its definition:
// a principal-point shift is a rotation of the camera frame (checked on projected points), and
// the first-order covariance matches the sample covariance of trajectories made with drawn
// calibration errors exactly (Q^T T Q, scaled translation), the error taken as the evaluation
// takes it (log(R^ R^T), t^ - t).
#include "slam/calibration_consider.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

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

// theta of a principal-point error (dcx, dcy) px (the header's model).
Vector3d thetaOf(double dcx, double dcy, double f) { return {-dcy / f, dcx / f, 0.0}; }

TEST(CalibrationConsider, PrincipalPointShiftIsARotationOfTheCameraFrame) {
  const double f = 700, cx = 600, cy = 180, dcx = 1.5, dcy = -2.0;
  const Matrix3d Q = pose(thetaOf(dcx, dcy, f), Vector3d::Zero()).linear();
  // Near the optical axis (bearings within about 0.1 rad): away from it a pixel shift of
  // f theta is a rotation of theta (1 + x^2), the header's model being its first order there.
  for (const Vector3d& X : {Vector3d(2, -1, 20), Vector3d(-1, 0.5, 15), Vector3d(0.5, 0.2, 40)}) {
    // Pixel of X through the true principal point, back-projected with the one the filter
    // has (cx + dcx, cy + dcy): the bearing the filter works with.
    const double u = f * X.x() / X.z() + cx, v = f * X.y() / X.z() + cy;
    const Vector3d b_hat = Vector3d((u - cx - dcx) / f, (v - cy - dcy) / f, 1).normalized();
    const Vector3d b_model = (Q.transpose() * X).normalized();
    EXPECT_LT((b_hat - b_model).norm(), 5e-5) << X.transpose();  // second order in theta
  }
}

TEST(CalibrationConsider, FirstOrderCovarianceMatchesDrawnCalibrationErrors) {
  const double f = 700;
  CalibrationConsiderParams p;
  p.sigma_principal_point_px = 1.0;
  p.sigma_scale = 0.002;
  const CalibrationConsider consider(p, f);
  ASSERT_TRUE(consider.initStatus());
  const Isometry3d T_wo = pose({0.1, -0.3, 0.2}, {5, -2, 30});
  for (const Isometry3d& T_oc : {pose({0.02, 0.3, -0.05}, {3, -1, 60}),
                                 pose({1.5, -0.8, 2.0}, {0.3, 0.2, -0.1}),
                                 pose({0.0, 3.0, 0.0}, {40, 0, -25})}) {
    const Isometry3d T_wc = T_wo * T_oc;
    Matrix6 cov;
    ASSERT_TRUE(consider.process(T_wo, T_wc, cov));
    std::mt19937_64 rng(42);
    std::normal_distribution<double> n(0.0, 1.0);
    Matrix6 sample = Matrix6::Zero();
    const int draws = 20000;
    for (int i = 0; i < draws; ++i) {
      const Matrix3d Q =
          pose(thetaOf(p.sigma_principal_point_px * n(rng), p.sigma_principal_point_px * n(rng), f),
               Vector3d::Zero())
              .linear();
      const double s = p.sigma_scale * n(rng);
      Isometry3d T_hat = Isometry3d::Identity();
      T_hat.linear() = Q.transpose() * T_oc.linear() * Q;
      T_hat.translation() = (1 + s) * (Q.transpose() * T_oc.translation());
      const Isometry3d T_wc_hat = T_wo * T_hat;
      Vector6 e;
      e.head<3>() = logRotation(T_wc_hat.linear() * T_wc.linear().transpose());
      e.tail<3>() = T_wc_hat.translation() - T_wc.translation();
      sample += e * e.transpose();
    }
    sample /= draws;
    // Sampling error of a variance with 20000 draws: about 1 %; the linearisation's is smaller.
    const double scale = cov.diagonal().maxCoeff();
    ASSERT_GT(scale, 0);
    EXPECT_LT((sample - cov).cwiseAbs().maxCoeff() / scale, 0.04)
        << "model\n" << cov << "\nsample\n" << sample;
  }
}

TEST(CalibrationConsider, ZeroAtTheOriginAndWhenExact) {
  CalibrationConsiderParams p;
  p.sigma_principal_point_px = 2.0;
  p.sigma_scale = 0.01;
  const Isometry3d T_wo = pose({0.4, 0.1, -0.2}, {1, 2, 3});
  Matrix6 cov;
  ASSERT_TRUE(CalibrationConsider(p, 500).process(T_wo, T_wo, cov));
  EXPECT_LT(cov.cwiseAbs().maxCoeff(), 1e-30);  // T_wo^-1 T_wo is the identity to rounding
  ASSERT_TRUE(CalibrationConsider(CalibrationConsiderParams{}, 500)
                  .process(T_wo, T_wo * pose({0.3, 0, 0}, {10, 0, 5}), cov));
  EXPECT_EQ(cov.cwiseAbs().maxCoeff(), 0.0);
  // A straight path along the optical axis: the principal point tilts it, the scale stretches
  // it; the attitude keeps no error.
  ASSERT_TRUE(CalibrationConsider(p, 500).process(Isometry3d::Identity(),
                                                  pose(Vector3d::Zero(), {0, 0, 100}), cov));
  EXPECT_NEAR(std::sqrt(cov(3, 3)), 100 * 2.0 / 500, 1e-12);
  EXPECT_NEAR(std::sqrt(cov(4, 4)), 100 * 2.0 / 500, 1e-12);
  EXPECT_NEAR(std::sqrt(cov(5, 5)), 100 * 0.01, 1e-12);
  const Matrix3d attitude = cov.topLeftCorner<3, 3>();
  EXPECT_EQ(attitude.cwiseAbs().maxCoeff(), 0.0);
}

TEST(CalibrationConsider, RejectsBadParametersAndPoses) {
  CalibrationConsiderParams p;
  p.sigma_principal_point_px = std::nan("");
  EXPECT_FALSE(CalibrationConsider(p, 500).initStatus());
  p.sigma_principal_point_px = -1;
  EXPECT_FALSE(CalibrationConsider(p, 500).initStatus());
  p = {};
  p.sigma_scale = 1.0;
  EXPECT_FALSE(CalibrationConsider(p, 500).initStatus());
  p = {};
  EXPECT_FALSE(CalibrationConsider(p, 0.0).initStatus());
  p.sigma_scale = 0.01;
  Isometry3d bad = Isometry3d::Identity();
  bad.translation().x() = std::nan("");
  Matrix6 cov = Matrix6::Ones();
  const Status s = CalibrationConsider(p, 500).process(Isometry3d::Identity(), bad, cov);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("non-finite"), std::string::npos);
  EXPECT_EQ(cov.cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace svslam

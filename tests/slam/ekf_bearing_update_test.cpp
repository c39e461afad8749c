// EkfSlam::updateBearings: against a dense EKF update with numerical Jacobians, Monte Carlo
// consistency of the pose when only bearings observe the map, gating and bad input.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "ekf_test_support.hpp"
#include "slam/ekf_slam.hpp"

namespace svslam {
namespace {

using namespace ekf_test;  // NOLINT: the shared fixtures
using Eigen::Isometry3d;
using Eigen::Matrix2d;
using Eigen::MatrixXd;
using Eigen::Vector2d;
using Eigen::Vector3d;
using Eigen::VectorXd;

Vector2d project(const Vector3d& p) { return {p.x() / p.z(), p.y() / p.z()}; }

// A filter with a correlated state: pose covariance, three landmarks added from the uncertain
// pose (so cross covariances exist), one prediction.
struct Fixture {
  EkfSlam ekf{EkfSlamParams{}};
  std::vector<int> ids;
  std::vector<Vector3d> z0 = {{1.0, -0.5, 6.0}, {-2.0, 0.3, 9.0}, {0.4, 1.2, 4.0}};
  Fixture() {
    const Matrix6d P0 =
        (Vector6d() << 1e-4, 2e-4, 1e-4, 1e-2, 2e-2, 1e-2).finished().asDiagonal();
    EXPECT_TRUE(ekf.reset(pose({0.05, -0.1, 0.02}, {0.3, -0.2, 1.0}), P0));
    for (const Vector3d& z : z0) ids.push_back(ekf.addLandmark(z, stereoCov(z)).value());
    EXPECT_TRUE(ekf.predict(pose({0.01, 0.02, -0.01}, {-0.1, 0.05, -0.3}), motionCov()));
  }
};

TEST(EkfBearingUpdate, MatchesDenseUpdateWithNumericalJacobians) {
  Fixture f;
  const int n = f.ekf.stateDim();
  const MatrixXd P = f.ekf.covariance();
  const Isometry3d T = f.ekf.pose();
  std::vector<Vector3d> m(3);
  Matrix3d C;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(f.ekf.landmark(f.ids[i], m[i], C));
  std::vector<BearingObservation> obs;
  const Matrix2d R = std::pow(0.7 / 700.0, 2) * Matrix2d::Identity();
  const Vector2d offsets[3] = {{0.004, -0.002}, {-0.003, 0.001}, {0.002, 0.003}};
  for (int i = 0; i < 3; ++i)
    obs.push_back({f.ids[i], project(observeLandmark(T, m[i])) + offsets[i], R});
  // Dense reference: h(x) stacked, H by central differences on the error state.
  const auto h = [&](const VectorXd& dx) {
    VectorXd z(6);
    const Isometry3d Tp = boxPlus(T, dx.head<6>());
    for (int i = 0; i < 3; ++i)
      z.segment<2>(2 * i) = project(observeLandmark(Tp, m[i] + dx.segment<3>(6 + 3 * i)));
    return z;
  };
  MatrixXd H(6, n);
  for (int k = 0; k < n; ++k) {
    VectorXd d = VectorXd::Zero(n);
    d(k) = 1e-6;
    H.col(k) = (h(d) - h(-d)) / 2e-6;
  }
  MatrixXd Rs = MatrixXd::Zero(6, 6);
  VectorXd nu(6);
  for (int i = 0; i < 3; ++i) {
    Rs.block<2, 2>(2 * i, 2 * i) = R;
    nu.segment<2>(2 * i) = obs[static_cast<std::size_t>(i)].xy;
  }
  nu -= h(VectorXd::Zero(n));
  const MatrixXd S = H * P * H.transpose() + Rs;
  const MatrixXd K = P * H.transpose() * S.inverse();
  const VectorXd dx = K * nu;
  const MatrixXd IKH = MatrixXd::Identity(n, n) - K * H;
  const MatrixXd P_ref = IKH * P * IKH.transpose() + K * Rs * K.transpose();

  std::vector<ObservationResult> res;
  ASSERT_TRUE(f.ekf.updateBearings(obs, res));
  ASSERT_EQ(res.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(res[static_cast<std::size_t>(i)].accepted);
    const Vector2d nu_i = nu.segment<2>(2 * i);
    const double d2 = nu_i.dot(S.block(2 * i, 2 * i, 2, 2).ldlt().solve(nu_i));
    EXPECT_NEAR(res[static_cast<std::size_t>(i)].mahalanobis_d2, d2, 1e-5 * d2);
  }
  EXPECT_LT((boxMinus(f.ekf.pose(), T) - dx.head<6>()).norm(), 1e-7);
  for (int i = 0; i < 3; ++i) {
    Vector3d mi;
    ASSERT_TRUE(f.ekf.landmark(f.ids[i], mi, C));
    EXPECT_LT((mi - m[i] - dx.segment<3>(6 + 3 * i)).norm(), 1e-7);
  }
  EXPECT_LT((f.ekf.covariance() - P_ref).norm(), 1e-6 * P.norm());
}

TEST(EkfBearingUpdate, BehindTheCameraIsNotApplied) {
  Fixture f;
  // Turn the camera around: every landmark is now behind it.
  ASSERT_TRUE(f.ekf.predict(pose({0, M_PI, 0}, {0, 0, 0}), Matrix6d::Identity() * 1e-8));
  const Isometry3d before = f.ekf.pose();
  std::vector<BearingObservation> obs = {{f.ids[0], Vector2d(0.1, 0.1),
                                          1e-6 * Matrix2d::Identity()}};
  std::vector<ObservationResult> res;
  ASSERT_TRUE(f.ekf.updateBearings(obs, res));
  EXPECT_FALSE(res[0].accepted);
  EXPECT_TRUE(std::isinf(res[0].mahalanobis_d2));
  EXPECT_TRUE(f.ekf.pose().isApprox(before));
}

TEST(EkfBearingUpdate, BadInputIsNamedAndChangesNothing) {
  Fixture f;
  const MatrixXd P = f.ekf.covariance();
  std::vector<ObservationResult> res;
  std::vector<BearingObservation> obs = {{f.ids[0], Vector2d(std::nan(""), 0), Matrix2d::Identity()}};
  Status s = f.ekf.updateBearings(obs, res);
  EXPECT_NE(s.message().find("xy is not finite"), std::string::npos) << s.message();
  obs = {{999, Vector2d(0, 0), Matrix2d::Identity()}};
  s = f.ekf.updateBearings(obs, res);
  EXPECT_NE(s.message().find("unknown landmark id 999"), std::string::npos) << s.message();
  obs = {{f.ids[0], Vector2d(0, 0), -Matrix2d::Identity()}};
  s = f.ekf.updateBearings(obs, res);
  EXPECT_NE(s.message().find("positive definite"), std::string::npos) << s.message();
  EXPECT_EQ(f.ekf.covariance(), P);
}

// Landmarks initialised by stereo in frames 0-2, then every frame observes them by bearing
// only (0.5 px with f = 700 px) while a VME-like motion predicts: the pose NEES averaged over
// 30 seeded runs stays inside the two-sided 95 % band of chi-square(6 runs) / runs.
TEST(EkfBearingUpdate, MonteCarloPoseNeesWithBearingsOnly) {
  const int runs = 30, frames = 25;
  const auto chi2q = [](double k, double zq) {
    const double a = 2.0 / (9.0 * k);
    return k * std::pow(1 - a + zq * std::sqrt(a), 3);
  };
  const double lo = chi2q(6.0 * runs, -1.959964) / runs, hi = chi2q(6.0 * runs, 1.959964) / runs;
  const double sigma_xy = 0.5 / calib().f_px;
  const Matrix2d R_xy = sigma_xy * sigma_xy * Matrix2d::Identity();
  std::vector<double> mean(frames, 0.0);
  for (int r = 0; r < runs; ++r) {
    std::mt19937 rng(2000 + static_cast<std::uint32_t>(r));
    std::uniform_real_distribution<double> ux(-8, 14), uy(-4, 4), uz(6, 25);
    std::normal_distribution<double> g(0, 1);
    std::vector<Vector3d> pts;
    for (int i = 0; i < 40; ++i) pts.emplace_back(ux(rng), uy(rng), uz(rng));
    const Matrix6d P0 =
        (Vector6d() << 1e-6, 1e-6, 1e-6, 1e-4, 1e-4, 1e-4).finished().asDiagonal();
    const Matrix6d R_u = motionCov();
    const Isometry3d step = pose({0.004, -0.01, 0.003}, {0.35, 0.02, 0.1});
    Isometry3d T_true = pose({0.02, 0.05, -0.01}, {0, 0, 0});
    EkfSlam ekf(EkfSlamParams{});
    ASSERT_TRUE(ekf.reset(boxPlus(T_true, -sample<6>(P0, rng)), P0));
    std::vector<int> id_of(pts.size(), -1);
    std::vector<LandmarkObservation> obs;
    std::vector<BearingObservation> bearings;
    std::vector<ObservationResult> res;
    for (int k = 0; k < frames; ++k) {
      if (k > 0) {
        T_true = T_true * step;
        ASSERT_TRUE(ekf.predict(boxPlus(step.inverse(), -sample<6>(R_u, rng)), R_u));
      }
      obs.clear();
      bearings.clear();
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const Vector3d p = T_true.inverse() * pts[i];
        if (!visible(p)) continue;
        if (id_of[i] < 0) {
          if (k < 3)
            id_of[i] = ekf.addLandmark(p + sample<3>(stereoCov(p), rng), stereoCov(p)).value();
          continue;
        }
        if (k < 3) {
          obs.push_back({id_of[i], p + sample<3>(stereoCov(p), rng), stereoCov(p)});
        } else {
          bearings.push_back({id_of[i], project(p) + sigma_xy * Vector2d(g(rng), g(rng)), R_xy});
        }
      }
      if (!obs.empty()) {
        ASSERT_TRUE(ekf.update(obs, res));
      }
      if (!bearings.empty()) {
        ASSERT_TRUE(ekf.updateBearings(bearings, res));
      }
      const Vector6d e = boxMinus(T_true, ekf.pose());
      mean[static_cast<std::size_t>(k)] += e.dot(ekf.poseCovariance().ldlt().solve(e)) / runs;
    }
  }
  std::printf("bearing-only pose NEES over %d runs (95 %% band [%.2f, %.2f]):", runs, lo, hi);
  for (int k : {4, 8, 12, 16, 20, 24}) {
    std::printf("  frame %d: %.2f", k, mean[static_cast<std::size_t>(k)]);
    EXPECT_GT(mean[static_cast<std::size_t>(k)], lo) << "frame " << k;
    EXPECT_LT(mean[static_cast<std::size_t>(k)], hi) << "frame " << k;
  }
  std::printf("\n");
}

}  // namespace
}  // namespace svslam

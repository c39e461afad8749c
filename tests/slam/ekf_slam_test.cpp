// EKF SLAM core (seed 001 sec. 4): exact composition of noise-free predictions, the sparse update
// against a dense textbook reference, gating of a planted outlier, positive definiteness over
// many updates, landmark removal, landmarks from an exact pose, restoration, the loop behaviour and
// bad-argument rejection. Jacobians: pose_jacobians_test.cpp; Monte Carlo consistency:
// ekf_slam_consistency_test.cpp.
#include "slam/ekf_slam.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "ekf_test_support.hpp"
#include "motion/visual_motion.hpp"
#include "slam/ekf_slam.hpp"
#include "slam/pose_jacobians.hpp"
#include "stereo/reprojection.hpp"

namespace svslam {
namespace {

using namespace ekf_test;  // NOLINT: the shared fixtures
using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;

// A filter holding `n` landmarks seen from a random pose with a correlated covariance.
EkfSlam filledFilter(int n, std::mt19937& rng, std::vector<Vector3d>* truth = nullptr,
                     EkfSlamParams params = {}) {
  EkfSlam ekf(params);
  EXPECT_TRUE(ekf.reset(pose({0.1, -0.2, 0.05}, {1, 0.5, -2}), motionCov()).isOk());
  std::uniform_real_distribution<double> x(-6, 6), y(-4, 4), z(4, 20);
  for (int i = 0; i < n; ++i) {
    const Vector3d p(x(rng), y(rng), z(rng));
    EXPECT_TRUE(ekf.addLandmark(p, stereoCov(p)).isOk());
    if (truth) truth->push_back(initLandmark(ekf.pose(), p));
  }
  EXPECT_TRUE(ekf.predict(pose({0.01, 0.02, -0.01}, {0.2, 0, -0.5}), motionCov()).isOk());
  return ekf;
}

TEST(EkfSlam, NoiseFreePredictionsComposeExactly) {
  std::mt19937 rng(3);
  EkfSlam a = filledFilter(10, rng), b = a;
  const Isometry3d u1 = pose({0.02, -0.05, 0.01}, {0.3, -0.1, 1.2});
  const Isometry3d u2 = pose({-0.03, 0.04, 0.02}, {-0.2, 0.1, 0.9});
  const MatrixXd P0 = a.covariance();
  Matrix6d F_x, F_u;
  predictionJacobians(a.pose(), u1, F_x, F_u);
  ASSERT_TRUE(a.predict(u1, Matrix6d::Zero()).isOk());
  // One step: F_x P_pp F_x^T on the pose block, F_x P_pm on the cross block, P_mm unchanged.
  const MatrixXd P1 = a.covariance();
  const int n = static_cast<int>(P0.rows());
  EXPECT_LT((P1.topLeftCorner<6, 6>() - F_x * P0.topLeftCorner<6, 6>() * F_x.transpose()).norm(),
            1e-12);
  EXPECT_LT((P1.topRightCorner(6, n - 6) - F_x * P0.topRightCorner(6, n - 6)).norm(), 1e-12);
  EXPECT_EQ(P1.bottomRightCorner(n - 6, n - 6), P0.bottomRightCorner(n - 6, n - 6));
  // Two steps equal one step with the composed motion T_cur_prev = u2 * u1.
  ASSERT_TRUE(a.predict(u2, Matrix6d::Zero()).isOk());
  ASSERT_TRUE(b.predict(u2 * u1, Matrix6d::Zero()).isOk());
  EXPECT_LT((a.pose().matrix() - b.pose().matrix()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((a.covariance() - b.covariance()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(EkfSlam, SparseUpdateMatchesDenseTextbookReference) {
  for (bool joseph : {true, false}) {
    std::mt19937 rng(5);
    EkfSlamParams params;
    params.joseph_form = joseph;
    EkfSlam ekf = filledFilter(12, rng, nullptr, params);
    const MatrixXd P = ekf.covariance();
    const int n = static_cast<int>(P.rows());
    Eigen::VectorXd x(n);
    x.head<6>().setZero();
    std::vector<LandmarkObservation> obs;
    for (int i = 0; i < 12; ++i) {
      Vector3d m;
      Matrix3d C;
      ASSERT_TRUE(ekf.landmark(ekf.landmarkIds()[static_cast<std::size_t>(i)], m, C).isOk());
      x.segment<3>(6 + 3 * i) = m;
      const Vector3d z = observeLandmark(ekf.pose(), m);
      if (i % 2 == 0 && i < 8)  // slots 0, 2, 4, 6
        obs.push_back({ekf.landmarkIds()[static_cast<std::size_t>(i)],
                       z + Vector3d(0.01, -0.02, 0.05), stereoCov(z)});
    }
    const int m = 12;
    MatrixXd H = MatrixXd::Zero(m, n), Rm = MatrixXd::Zero(m, m);
    Eigen::VectorXd nu(m);
    for (int j = 0; j < 4; ++j) {
      const int s = 2 * j;
      Matrix36d H_p;
      Matrix3d H_m;
      observationJacobians(ekf.pose(), x.segment<3>(6 + 3 * s), H_p, H_m);
      H.block<3, 6>(3 * j, 0) = H_p;
      H.block<3, 3>(3 * j, 6 + 3 * s) = H_m;
      Rm.block<3, 3>(3 * j, 3 * j) = obs[static_cast<std::size_t>(j)].R;
      nu.segment<3>(3 * j) = obs[static_cast<std::size_t>(j)].z_cam -
                             observeLandmark(ekf.pose(), x.segment<3>(6 + 3 * s));
    }
    const MatrixXd S = H * P * H.transpose() + Rm;
    const MatrixXd K = P * H.transpose() * S.inverse();
    const MatrixXd IKH = MatrixXd::Identity(n, n) - K * H;
    const MatrixXd P_ref = IKH * P * IKH.transpose() + K * Rm * K.transpose();
    const Eigen::VectorXd dx = K * nu;
    const Isometry3d T_ref = boxPlus(ekf.pose(), dx.head<6>());
    std::vector<ObservationResult> res;
    ASSERT_TRUE(ekf.update(obs, res).isOk());
    for (const auto& r : res) EXPECT_TRUE(r.accepted);
    EXPECT_LT((ekf.covariance() - P_ref).cwiseAbs().maxCoeff(),
              1e-12 * P.cwiseAbs().maxCoeff() * 1e3);
    EXPECT_LT((ekf.pose().matrix() - T_ref.matrix()).cwiseAbs().maxCoeff(), 1e-10);
    Vector3d m0;
    Matrix3d C0;
    ASSERT_TRUE(ekf.landmark(ekf.landmarkIds()[2], m0, C0).isOk());
    EXPECT_LT((m0 - x.segment<3>(12) - dx.segment<3>(12)).norm(), 1e-10);
  }
}

TEST(EkfSlam, GatingRejectsPlantedOutlierAndLeavesStateUnaffected) {
  std::mt19937 rng(11);
  std::vector<Vector3d> truth;
  EkfSlam with = filledFilter(15, rng, &truth), without = with;
  std::vector<LandmarkObservation> obs;
  for (int i = 0; i < 15; ++i) {
    const Vector3d p = observeLandmark(with.pose(), truth[static_cast<std::size_t>(i)]);
    obs.push_back({with.landmarkIds()[static_cast<std::size_t>(i)],
                   p + sample<3>(stereoCov(p), rng), stereoCov(p)});
  }
  const std::vector<LandmarkObservation> clean = obs;
  obs.insert(obs.begin() + 7, obs[7]);
  obs[7].z_cam += Vector3d(1.0, 0, 0);  // the outlier: 1 m off
  std::vector<ObservationResult> res, res_clean;
  ASSERT_TRUE(with.update(obs, res).isOk());
  ASSERT_TRUE(without.update(clean, res_clean).isOk());
  ASSERT_EQ(res.size(), obs.size());
  EXPECT_FALSE(res[7].accepted);
  EXPECT_GT(res[7].mahalanobis_d2, 11.34);
  std::printf("outlier d2 = %.1f\n", res[7].mahalanobis_d2);
  for (std::size_t k = 0; k < res_clean.size(); ++k) EXPECT_TRUE(res_clean[k].accepted) << k;
  EXPECT_TRUE(with.pose().matrix() == without.pose().matrix());
  EXPECT_TRUE(with.covariance() == without.covariance());
}

// Many updates hovering among the same landmarks with precise observations (P shrinks by orders
// of magnitude): P must stay symmetric positive definite.
TEST(EkfSlam, CovarianceStaysSymmetricPositiveDefinite) {
  for (bool joseph : {true, false}) {
    std::mt19937 rng(17);
    std::vector<Vector3d> truth;
    EkfSlamParams params;
    params.joseph_form = joseph;
    params.max_batch_observations = 16;  // 30 observations: two batches per frame
    EkfSlam ekf = filledFilter(30, rng, &truth, params);
    Isometry3d T_true = ekf.pose();
    const Matrix6d R_u = 1e-4 * motionCov();
    std::vector<LandmarkObservation> obs;
    std::vector<ObservationResult> res;
    for (int k = 0; k < 300; ++k) {
      const Isometry3d u = pose({0.001, -0.002, 0.001}, {0.01, 0.0, -0.01});
      T_true = predictPose(T_true, u);
      ASSERT_TRUE(ekf.predict(boxPlus(u, -sample<6>(R_u, rng)), R_u).isOk());
      obs.clear();
      for (int i = 0; i < 30; ++i) {
        const Vector3d p = observeLandmark(T_true, truth[static_cast<std::size_t>(i)]);
        const Matrix3d C = 1e-4 * stereoCov(p);
        obs.push_back({ekf.landmarkIds()[static_cast<std::size_t>(i)], p + sample<3>(C, rng), C});
      }
      ASSERT_TRUE(ekf.update(obs, res).isOk());
    }
    const MatrixXd P = ekf.covariance();
    ASSERT_TRUE(P.allFinite());
    EXPECT_EQ(P, P.transpose());
    const Eigen::SelfAdjointEigenSolver<MatrixXd> es(P, Eigen::EigenvaluesOnly);
    std::printf("%s: eigenvalues of P in [%.3g, %.3g] after 300 frames\n",
                joseph ? "Joseph" : "optimal-gain", es.eigenvalues().minCoeff(),
                es.eigenvalues().maxCoeff());
    EXPECT_GT(es.eigenvalues().minCoeff(), 0);
  }
}

TEST(EkfSlam, RemoveLandmarkReturnsItsEstimateAndKeepsTheRest) {
  std::mt19937 rng(23);
  EkfSlam ekf = filledFilter(6, rng);
  const std::vector<int> ids = ekf.landmarkIds();
  const MatrixXd P = ekf.covariance();
  std::vector<Vector3d> m(6);
  for (int i = 0; i < 6; ++i) {
    Matrix3d C;
    ASSERT_TRUE(
        ekf.landmark(ids[static_cast<std::size_t>(i)], m[static_cast<std::size_t>(i)], C).isOk());
  }
  Vector3d m_out;
  Matrix3d C_out;
  ASSERT_TRUE(ekf.removeLandmark(ids[1], &m_out, &C_out).isOk());
  EXPECT_EQ(m_out, m[1]);
  EXPECT_EQ(C_out, (P.block<3, 3>(9, 9)));
  // ids[5] moved into slot 1; ids[4] is now the last slot (removal without a move).
  ASSERT_TRUE(ekf.removeLandmark(ids[4], nullptr, nullptr).isOk());
  EXPECT_EQ(ekf.numLandmarks(), 4);
  EXPECT_EQ(ekf.removeLandmark(ids[1], nullptr, nullptr).code(), StatusCode::kNotFound);
  // The rest: the same rows/columns of the old P in the new state order.
  const MatrixXd Pn = ekf.covariance();
  ASSERT_EQ(Pn.rows(), 18);
  for (int a = 0; a < 6 + 12; ++a) {
    for (int b = 0; b < 6 + 12; ++b) {
      auto map = [&](int r) {
        if (r < 6) return r;
        const int id = ekf.landmarkIds()[static_cast<std::size_t>((r - 6) / 3)];
        const int i = static_cast<int>(std::find(ids.begin(), ids.end(), id) - ids.begin());
        return 6 + 3 * i + (r - 6) % 3;
      };
      ASSERT_EQ(Pn(a, b), P(map(a), map(b))) << a << " " << b;
    }
  }
  for (int id : ekf.landmarkIds()) {
    Vector3d p;
    Matrix3d C;
    ASSERT_TRUE(ekf.landmark(id, p, C).isOk());
    EXPECT_EQ(p, m[static_cast<std::size_t>(std::find(ids.begin(), ids.end(), id) - ids.begin())]);
  }
  // New landmarks get new ids and an update still works on the compacted state.
  const int new_id = ekf.addLandmark(Vector3d(1, 0, 8), stereoCov(Vector3d(1, 0, 8))).value();
  EXPECT_GT(new_id, ids.back());
  std::vector<ObservationResult> res;
  ASSERT_TRUE(ekf.update({{new_id, Vector3d(1, 0, 8), stereoCov(Vector3d(1, 0, 8))}}, res).isOk());
}

// A move of the world frame (loop-closing correction): pose and landmarks move rigidly,
// P <- J P J^T with J = diag(R_c, ..., R_c), and everything the filter computes relative to the
// camera is unchanged: the same observations give the same innovations, gating and relative
// state after the update.
TEST(EkfSlam, TransformWorldMovesStateAndCovarianceRigidly) {
  std::mt19937 rng(31);
  EkfSlam a = filledFilter(5, rng);
  EkfSlam b = a;
  const Isometry3d C = pose({0.03, -0.02, 0.15}, {2.0, -1.5, 0.4});
  const MatrixXd P = a.covariance();
  ASSERT_TRUE(b.transformWorld(C).isOk());
  EXPECT_TRUE(b.pose().isApprox(C * a.pose(), 1e-12));
  const int n = a.stateDim();
  MatrixXd J = MatrixXd::Zero(n, n);
  for (int k = 0; k < n / 3; ++k) J.block<3, 3>(3 * k, 3 * k) = C.linear();
  EXPECT_LT((b.covariance() - J * P * J.transpose()).norm(), 1e-12 * P.norm());
  for (int id : a.landmarkIds()) {
    Vector3d pa, pb;
    Matrix3d Ca, Cb;
    ASSERT_TRUE(a.landmark(id, pa, Ca).isOk());
    ASSERT_TRUE(b.landmark(id, pb, Cb).isOk());
    EXPECT_LT((pb - C * pa).norm(), 1e-12);
  }
  // The same camera-frame observations (one planted outlier) on both.
  std::vector<LandmarkObservation> obs;
  std::normal_distribution<double> noise(0, 0.02);
  for (int id : a.landmarkIds()) {
    Vector3d m;
    Matrix3d Cm;
    ASSERT_TRUE(a.landmark(id, m, Cm).isOk());
    const Vector3d z = a.pose().inverse() * m + Vector3d(noise(rng), noise(rng), noise(rng));
    obs.push_back({id, z, stereoCov(z)});
  }
  obs[2].z_cam += Vector3d(3, 0, 0);
  std::vector<ObservationResult> ra, rb;
  ASSERT_TRUE(a.update(obs, ra).isOk());
  ASSERT_TRUE(b.update(obs, rb).isOk());
  ASSERT_EQ(ra.size(), rb.size());
  for (std::size_t k = 0; k < ra.size(); ++k) {
    EXPECT_EQ(ra[k].accepted, rb[k].accepted);
    EXPECT_NEAR(ra[k].mahalanobis_d2, rb[k].mahalanobis_d2, 1e-6 * (1 + ra[k].mahalanobis_d2));
  }
  EXPECT_FALSE(ra[2].accepted);
  EXPECT_TRUE(b.pose().isApprox(C * a.pose(), 1e-9));
  EXPECT_LT((b.covariance() - J * a.covariance() * J.transpose()).norm(),
            1e-9 * a.covariance().norm());
  // Not a rigid transform: refused, nothing changed.
  Isometry3d bad = C;
  bad.linear() *= 1.1;
  const Isometry3d before = b.pose();
  EXPECT_EQ(b.transformWorld(bad).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(b.pose().matrix(), before.matrix());
}

// A direct position measurement (loop-closing correction) against the dense textbook update on
// the full state: x (+) K z, P - K H P with H = [0 I3 0], and the attitude and the landmarks
// follow the position through their cross covariances.
TEST(EkfSlam, PositionMeasurementMatchesDenseTextbookUpdate) {
  std::mt19937 rng(37);
  EkfSlam ekf = filledFilter(4, rng);
  const MatrixXd P = ekf.covariance();
  const int n = ekf.stateDim();
  const Isometry3d T0 = ekf.pose();
  std::vector<Vector3d> m0;
  for (int id : ekf.landmarkIds()) {
    Vector3d m;
    Matrix3d C;
    ASSERT_TRUE(ekf.landmark(id, m, C).isOk());
    m0.push_back(m);
  }
  const Vector3d t_meas = T0.translation() + Vector3d(0.3, -0.1, 0.2);
  const Matrix3d R = Matrix3d::Identity() * 1e-3;
  MatrixXd H = MatrixXd::Zero(3, n);
  H.block<3, 3>(0, 3).setIdentity();
  const MatrixXd S = H * P * H.transpose() + R;
  const MatrixXd K = P * H.transpose() * S.inverse();
  const Vector3d z = t_meas - T0.translation();
  const Eigen::VectorXd dx = K * z;
  const MatrixXd P_ref = P - K * H * P;
  double d2 = -1;
  ASSERT_TRUE(ekf.updatePosition(t_meas, R, &d2).isOk());
  EXPECT_NEAR(d2, z.dot(S.inverse() * z), 1e-9);
  EXPECT_LT((ekf.covariance() - P_ref).norm(), 1e-10 * P.norm());
  EXPECT_TRUE(ekf.pose().isApprox(boxPlus(T0, dx.head<6>()), 1e-12));
  EXPECT_GT(dx.head<3>().norm(), 0.0);  // the attitude moved through the correlation
  for (std::size_t i = 0; i < m0.size(); ++i) {
    Vector3d m;
    Matrix3d C;
    ASSERT_TRUE(ekf.landmark(ekf.landmarkIds()[i], m, C).isOk());
    EXPECT_LT((m - (m0[i] + dx.segment<3>(6 + 3 * static_cast<int>(i)))).norm(), 1e-12);
  }
  EXPECT_GT((ekf.pose().translation() - T0.translation()).norm(), 1e-3);  // it moved
  // Bad inputs: refused, nothing changed.
  const Isometry3d before = ekf.pose();
  EXPECT_EQ(ekf.updatePosition(t_meas, -R).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ekf.updatePosition(Vector3d(NAN, 0, 0), R).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ekf.pose().matrix(), before.matrix());
}

// Loop: landmarks near the start, a long excursion with prediction only, then re-perception of
// the first landmarks (1 px matching error, seed 001 sec. 4.1): the pose covariance shrinks.
// A landmark measured from an exactly known pose: the same as addLandmark on a filter whose
// pose covariance is zero (eqs. 4-5 with P_pose = 0), with no cross covariance.
TEST(EkfSlam, LandmarkFromExactPoseIsIndependentOfTheState) {
  std::mt19937 rng(11);
  EkfSlam ekf = filledFilter(4, rng);
  const Isometry3d T0 = pose({0.05, -0.1, 0.2}, {2, -1, 0.5});
  const Vector3d z(1.5, -0.7, 12.0);
  const Matrix3d R_z = stereoCov(z);
  const int id = ekf.addLandmarkFromExactPose(T0, z, R_z).value();
  EkfSlam ref{EkfSlamParams{}};
  ASSERT_TRUE(ref.reset(T0, Matrix6d::Zero()).isOk());
  const int ref_id = ref.addLandmark(z, R_z).value();
  Vector3d m, m_ref;
  Matrix3d C, C_ref;
  ASSERT_TRUE(ekf.landmark(id, m, C).isOk());
  ASSERT_TRUE(ref.landmark(ref_id, m_ref, C_ref).isOk());
  EXPECT_LT((m - m_ref).norm(), 1e-12);
  EXPECT_LT((C - C_ref).norm(), 1e-15);
  const MatrixXd P = ekf.covariance();
  const int o = 6 + 3 * 4;
  EXPECT_EQ(P.block(o, 0, 3, o).norm(), 0.0);
  EXPECT_EQ(P.block(0, o, o, 3).norm(), 0.0);
  EXPECT_EQ(ekf.addLandmarkFromExactPose(T0, Vector3d(0, NAN, 5), R_z).status().code(),
            StatusCode::kInvalidArgument);
  EkfSlamParams small;
  small.max_landmarks = 1;
  EkfSlam full(small);
  ASSERT_TRUE(full.addLandmarkFromExactPose(T0, z, R_z).isOk());
  EXPECT_EQ(full.addLandmarkFromExactPose(T0, z, R_z).status().code(),
            StatusCode::kFailedPrecondition);
}

// A removed landmark comes back under its id with the estimate it left with, no cross
// covariance, and takes part in updates again.
TEST(EkfSlam, RestoredLandmarkComesBackUnderItsId) {
  std::mt19937 rng(12);
  std::vector<Vector3d> truth;
  EkfSlam ekf = filledFilter(5, rng, &truth);
  const std::vector<int> ids = ekf.landmarkIds();
  Vector3d m;
  Matrix3d C;
  ASSERT_TRUE(ekf.removeLandmark(ids[2], &m, &C).isOk());
  ASSERT_TRUE(ekf.predict(pose({0.01, 0, 0.02}, {0.3, 0.1, 0}), motionCov()).isOk());
  EXPECT_EQ(ekf.restoreLandmark(ids[3], m, C).code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(ekf.restoreLandmark(999, m, C).code(), StatusCode::kNotFound);
  EXPECT_EQ(ekf.restoreLandmark(ids[2], Vector3d(NAN, 0, 0), C).code(),
            StatusCode::kInvalidArgument);
  ASSERT_TRUE(ekf.restoreLandmark(ids[2], m, C).isOk());
  EXPECT_EQ(ekf.restoreLandmark(ids[2], m, C).code(), StatusCode::kFailedPrecondition);
  Vector3d m2;
  Matrix3d C2;
  ASSERT_TRUE(ekf.landmark(ids[2], m2, C2).isOk());
  EXPECT_EQ(m2, m);
  EXPECT_EQ(C2, C);
  const MatrixXd P = ekf.covariance();
  const int o = 6 + 3 * 4;  // the last slot
  EXPECT_EQ(P.block(o, 0, 3, o).norm(), 0.0);
  // Observed at its true position from the current pose, it updates the filter.
  const Vector3d z = ekf.pose().inverse() * truth[2];
  std::vector<ObservationResult> res;
  ASSERT_TRUE(ekf.update({{ids[2], z, stereoCov(z)}}, res).isOk());
  EXPECT_TRUE(res[0].accepted);
  ASSERT_TRUE(ekf.landmark(ids[2], m2, C2).isOk());
  EXPECT_LT(C2.trace(), C.trace());
  const MatrixXd Pu = ekf.covariance();
  EXPECT_LT((Pu - Pu.transpose()).norm(), 1e-12);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatrixXd>(Pu).eigenvalues().minCoeff(), 0.0);
}

TEST(EkfSlam, ReobservingFirstLandmarksAfterALoopShrinksPoseCovariance) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> ux(-6, 6), uy(-3, 3), uz(8, 20);
  std::vector<Vector3d> pts;
  for (int i = 0; i < 25; ++i) pts.emplace_back(ux(rng), uy(rng), uz(rng));
  EkfSlam ekf(EkfSlamParams{});
  ASSERT_TRUE(ekf.reset(Isometry3d::Identity(), Matrix6d::Zero()).isOk());
  for (const auto& p : pts)
    ASSERT_TRUE(ekf.addLandmark(p + sample<3>(stereoCov(p), rng), stereoCov(p)).isOk());
  // 40 steps around a square of side 10 m (turning 90 degrees every 10 steps), back at the start.
  Isometry3d T_true = Isometry3d::Identity();
  const Matrix6d R_u = motionCov();
  for (int k = 0; k < 40; ++k) {
    const Isometry3d step =
        pose({0, (k % 10 == 9) ? M_PI / 2 : 0.0, 0}, {0, 0, 1.0});  // T_prev_cur
    T_true = T_true * step;
    ASSERT_TRUE(ekf.predict(boxPlus(step.inverse(), -sample<6>(R_u, rng)), R_u).isOk());
  }
  const double before = ekf.poseCovariance().trace();
  std::vector<LandmarkObservation> obs;
  for (int i = 0; i < 25; ++i) {
    const Vector3d p = T_true.inverse() * pts[static_cast<std::size_t>(i)];
    if (!visible(p)) continue;
    obs.push_back({ekf.landmarkIds()[static_cast<std::size_t>(i)],
                   p + sample<3>(stereoCov(p, 1.0), rng), stereoCov(p, 1.0)});
  }
  ASSERT_GE(obs.size(), 10u);
  std::vector<ObservationResult> res;
  ASSERT_TRUE(ekf.update(obs, res).isOk());
  const double after = ekf.poseCovariance().trace();
  const Vector6d e = boxMinus(T_true, ekf.pose());
  std::printf("loop: pose covariance trace %.3g -> %.3g (factor %.0f), position error %.3f m\n",
              before, after, before / after, e.tail<3>().norm());
  EXPECT_GT(before / after, 20.0);
  EXPECT_LT(e.dot(ekf.poseCovariance().ldlt().solve(e)), 22.46);  // chi-square 6 dof, 99.9 %
}

TEST(EkfSlam, RejectsBadInputsAndStaysUntouched) {
  EkfSlamParams bad;
  bad.max_landmarks = 0;
  EXPECT_FALSE(EkfSlam(bad).initStatus().isOk());
  bad = {};
  bad.gate_chi2 = -1;
  EXPECT_EQ(EkfSlam(bad).addLandmark(Vector3d(0, 0, 5), Matrix3d::Identity()).status().code(),
            StatusCode::kInvalidArgument);
  std::mt19937 rng(31);
  EkfSlamParams small;
  small.max_landmarks = 3;
  EkfSlam ekf = filledFilter(3, rng, nullptr, small);
  const MatrixXd P = ekf.covariance();
  const Isometry3d T = ekf.pose();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const int id = ekf.landmarkIds()[0];
  std::vector<ObservationResult> res;
  auto expectInvalid = [&](const Status& s, const char* what) {
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << what;
    EXPECT_NE(s.message().find(what), std::string::npos) << s.message();
  };
  expectInvalid(ekf.update({{id, Vector3d(nan, 0, 5), Matrix3d::Identity()}}, res), "z_cam");
  expectInvalid(ekf.update({{id, Vector3d(0, 0, 5), Matrix3d::Zero()}}, res), "positive definite");
  expectInvalid(ekf.update({{99, Vector3d(0, 0, 5), Matrix3d::Identity()}}, res),
                "unknown landmark id 99");
  Isometry3d Tn = Isometry3d::Identity();
  Tn.translation().x() = nan;
  expectInvalid(ekf.predict(Tn, Matrix6d::Identity()), "T_cur_prev");
  Isometry3d Ts = Isometry3d::Identity();
  Ts.linear() *= 1.1;
  expectInvalid(ekf.predict(Ts, Matrix6d::Identity()), "rotation");
  Matrix6d A = Matrix6d::Identity();
  A(0, 1) = 0.5;
  expectInvalid(ekf.predict(Isometry3d::Identity(), A), "symmetric");
  expectInvalid(ekf.predict(Isometry3d::Identity(), -Matrix6d::Identity()), "semi-definite");
  expectInvalid(ekf.reset(Isometry3d::Identity(), Matrix6d::Constant(nan)), "P0");
  expectInvalid(ekf.addLandmark(Vector3d(0, nan, 5), Matrix3d::Identity()).status(), "z_cam");
  EXPECT_TRUE(ekf.pose().matrix() == T.matrix());
  EXPECT_TRUE(ekf.covariance() == P);
  EXPECT_EQ(ekf.addLandmark(Vector3d(0, 0, 5), Matrix3d::Identity()).status().code(),
            StatusCode::kFailedPrecondition);  // full
  ASSERT_TRUE(ekf.removeLandmark(id, nullptr, nullptr).isOk());
  Vector3d m;
  Matrix3d C;
  EXPECT_EQ(ekf.landmark(id, m, C).code(), StatusCode::kNotFound);
  EXPECT_TRUE(ekf.addLandmark(Vector3d(0, 0, 5), Matrix3d::Identity()).isOk());
}

}  // namespace
}  // namespace svslam

// EKF SLAM consistency (seed 001 sec. 4): the pose NEES over seeded Monte Carlo runs of a
// simulated sequence stays inside the chi-square 95 % band.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
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
using Eigen::Vector3d;

// Wilson-Hilferty quantile of chi-square with k dof at the standard normal quantile zq.
double chi2Quantile(double k, double zq) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1 - a + zq * std::sqrt(a), 3);
}

// One run of the simulated sequence: camera translating sideways and forward among 40 points,
// landmarks initialised in frames 0-2, updates afterwards. Returns the pose NEES per frame.
// The observation covariance given to the filter is that of the noise actually drawn (stereo
// covariance at the true point) when cov_at_truth, else the one computed at the measured point.
std::vector<double> simulateRun(std::uint32_t seed, int frames, bool cov_at_truth) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-8, 14), uy(-4, 4), uz(6, 25);
  std::vector<Vector3d> pts;
  for (int i = 0; i < 40; ++i) pts.emplace_back(ux(rng), uy(rng), uz(rng));
  const Matrix6d P0 = (Vector6d() << 1e-6, 1e-6, 1e-6, 1e-4, 1e-4, 1e-4).finished().asDiagonal();
  const Matrix6d R_u = motionCov();
  const Isometry3d step = pose({0.004, -0.01, 0.003}, {0.35, 0.02, 0.1});  // T_prev_cur
  Isometry3d T_true = pose({0.02, 0.05, -0.01}, {0, 0, 0});
  EkfSlam ekf(EkfSlamParams{});
  EXPECT_TRUE(ekf.reset(boxPlus(T_true, -sample<6>(P0, rng)), P0).isOk());
  std::vector<int> id_of(pts.size(), -1);
  std::vector<double> nees;
  std::vector<LandmarkObservation> obs;
  std::vector<ObservationResult> res;
  for (int k = 0; k < frames; ++k) {
    if (k > 0) {
      T_true = T_true * step;
      const Isometry3d u_true = step.inverse();
      EXPECT_TRUE(ekf.predict(boxPlus(u_true, -sample<6>(R_u, rng)), R_u).isOk());
    }
    obs.clear();
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const Vector3d p = T_true.inverse() * pts[i];
      if (!visible(p)) continue;
      const Vector3d z = p + sample<3>(stereoCov(p), rng);
      if (id_of[i] >= 0) {
        obs.push_back({id_of[i], z, stereoCov(cov_at_truth ? p : z)});
      } else if (k < 3) {
        id_of[i] = ekf.addLandmark(z, stereoCov(cov_at_truth ? p : z)).value();
      }
    }
    if (k > 0) {
      EXPECT_TRUE(ekf.update(obs, res).isOk());
    }
    const Vector6d e = boxMinus(T_true, ekf.pose());
    nees.push_back(e.dot(ekf.poseCovariance().ldlt().solve(e)));
  }
  return nees;
}

// Average NEES of the 6-dof pose error over 30 runs inside the two-sided 95 % band of
// chi-square(6 runs) / runs. Also printed (not asserted): the same runs with the covariance
// computed at the measured point, as a real front end does (depth-dependent noise makes near-
// measured points look more precise, a mild overconfidence).
TEST(EkfSlam, MonteCarloPoseNeesInsideChiSquareBand) {
  const int runs = 30, frames = 25;
  const double lo = chi2Quantile(6.0 * runs, -1.959964) / runs,
               hi = chi2Quantile(6.0 * runs, 1.959964) / runs;
  std::printf("pose NEES averaged over %d runs (95 %% band [%.2f, %.2f]):\n", runs, lo, hi);
  for (bool cov_at_truth : {true, false}) {
    std::vector<double> mean(frames, 0.0);
    for (int r = 0; r < runs; ++r) {
      const auto nees = simulateRun(1000 + static_cast<std::uint32_t>(r), frames, cov_at_truth);
      for (int k = 0; k < frames; ++k)
        mean[static_cast<std::size_t>(k)] += nees[static_cast<std::size_t>(k)] / runs;
    }
    std::printf("  R at the %s point:", cov_at_truth ? "true" : "measured");
    for (int k : {4, 8, 12, 16, 20, 24}) {
      std::printf("  frame %d: %.2f", k, mean[static_cast<std::size_t>(k)]);
      if (!cov_at_truth) continue;
      EXPECT_GT(mean[static_cast<std::size_t>(k)], lo) << "frame " << k;
      EXPECT_LT(mean[static_cast<std::size_t>(k)], hi) << "frame " << k;
    }
    std::printf("\n");
  }
}

}  // namespace
}  // namespace svslam

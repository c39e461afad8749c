#pragma once
// Synthetic keyframe trajectories for the loop-closing tests: a circle (radius 20 m, gentle
// height and attitude oscillations) driven `laps` times, odometry edges with noise drawn from
// their covariance (seeded) and the drifting chain they integrate to.
#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "motion/visual_motion.hpp"
#include "slam/pose_jacobians.hpp"

namespace svslam::loop_test {

inline Matrix6d diagCov(double sigma_rot_rad, double sigma_trans_m) {
  Vector6d v;
  v << Eigen::Vector3d::Constant(sigma_rot_rad * sigma_rot_rad),
      Eigen::Vector3d::Constant(sigma_trans_m * sigma_trans_m);
  return v.asDiagonal();
}

// A sample of N(0, C).
inline Vector6d sampleNoise(const Matrix6d& C, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Vector6d z;
  for (int i = 0; i < 6; ++i) z[i] = n(rng);
  return Matrix6d(C.llt().matrixL()) * z;
}

// T_world_kf of keyframe k of `per_lap` keyframes per lap.
inline Eigen::Isometry3d circlePose(int k, int per_lap, double radius_m = 20.0) {
  const double a = 2 * M_PI * k / per_lap;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() =
      Eigen::Vector3d(radius_m * std::cos(a), radius_m * std::sin(a), 0.5 * std::sin(3 * a));
  T.linear() = expSO3(Eigen::Vector3d(0, 0, a + M_PI / 2)) *
               expSO3(Eigen::Vector3d(0.05 * std::sin(2 * a), 0.03 * std::cos(5 * a), 0));
  return T;
}

struct Scene {
  std::vector<Eigen::Isometry3d> truth;     // T_world_kf
  std::vector<Eigen::Isometry3d> odo_meas;  // noisy T_k_(k+1)
  std::vector<Matrix6d> odo_cov;            // their covariances
  std::vector<Eigen::Isometry3d> odometry;  // the chain integrated from truth[0]
};

inline Scene makeScene(int keyframes, int per_lap, const Matrix6d& odo_cov, std::uint32_t seed) {
  std::mt19937 rng(seed);
  Scene s;
  for (int k = 0; k < keyframes; ++k) s.truth.push_back(circlePose(k, per_lap));
  s.odometry.push_back(s.truth[0]);
  for (int k = 0; k + 1 < keyframes; ++k) {
    const Eigen::Isometry3d E = s.truth[k].inverse() * s.truth[k + 1];
    s.odo_meas.push_back(boxPlus(E, sampleNoise(odo_cov, rng)));
    s.odo_cov.push_back(odo_cov);
    s.odometry.push_back(s.odometry.back() * s.odo_meas.back());
  }
  return s;
}

// Root mean square position error (m) of est against truth (no alignment: both start at the
// same first pose).
inline double ateRmse(const std::vector<Eigen::Isometry3d>& est,
                      const std::vector<Eigen::Isometry3d>& truth) {
  double sum = 0;
  for (std::size_t k = 0; k < est.size(); ++k)
    sum += (est[k].translation() - truth[k].translation()).squaredNorm();
  return std::sqrt(sum / static_cast<double>(est.size()));
}

}  // namespace svslam::loop_test

#pragma once
// Shared fixtures of the EKF SLAM tests: a stereo camera, the stereo covariance of a point,
// visibility, Gaussian sampling, poses, a VME-like motion covariance, numerical Jacobians.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>

#include "core/camera.hpp"
#include "motion/visual_motion.hpp"
#include "slam/pose_jacobians.hpp"
#include "stereo/reprojection.hpp"

namespace svslam::ekf_test {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;

inline StereoCalibration calib() { return {700.0, 320.0, 240.0, 0.5, 640, 480}; }

// Stereo covariance of a camera-frame point: disparity sigma 0.3 px, image plane `sigma_uv` px.
inline Matrix3d stereoCov(const Vector3d& p, double sigma_uv = 0.5) {
  const auto c = calib();
  const double u = c.f_px * p.x() / p.z() + c.cx_px, v = c.f_px * p.y() / p.z() + c.cy_px;
  return reprojectPixel(c, u, v, c.f_px * c.baseline_m / p.z(), 0.3, sigma_uv).cov;
}

inline bool visible(const Vector3d& p) {
  const auto c = calib();
  if (p.z() < 2.0) return false;
  const double u = c.f_px * p.x() / p.z() + c.cx_px, v = c.f_px * p.y() / p.z() + c.cy_px;
  return u > 10 && u < c.width - 10 && v > 10 && v < c.height - 10;
}

template <int N>
Eigen::Matrix<double, N, 1> sample(const Eigen::Matrix<double, N, N>& cov, std::mt19937& rng) {
  std::normal_distribution<double> g(0, 1);
  Eigen::Matrix<double, N, 1> n;
  for (int i = 0; i < N; ++i) n(i) = g(rng);
  return Eigen::Matrix<double, N, N>(cov.llt().matrixL()) * n;
}

inline Isometry3d pose(const Vector3d& w, const Vector3d& t) {
  Isometry3d T = Isometry3d::Identity();
  T.linear() = expSO3(w);
  T.translation() = t;
  return T;
}

// VME-like motion covariance [dtheta, dt]: 2 mrad, 2 cm, rotation/translation coupled.
inline Matrix6d motionCov() {
  Matrix6d C = Matrix6d::Identity();
  C(1, 3) = C(3, 1) = 0.6;
  C(0, 4) = C(4, 0) = -0.6;
  const Vector6d s = (Vector6d() << 2e-3, 2e-3, 1e-3, 0.02, 0.02, 0.01).finished();
  return s.asDiagonal() * C * s.asDiagonal();
}

// Central differences of f (R^k -> R^r) at 0.
template <int R, int K, class F>
Eigen::Matrix<double, R, K> numericJacobian(F f) {
  Eigen::Matrix<double, R, K> J;
  const double h = 1e-6;
  for (int k = 0; k < K; ++k) {
    Eigen::Matrix<double, K, 1> d = Eigen::Matrix<double, K, 1>::Zero();
    d(k) = h;
    J.col(k) = (f(d) - f(-d)) / (2 * h);
  }
  return J;
}

}  // namespace svslam::ekf_test

#pragma once
// Visual motion estimation from 3D-3D correspondences (seed 001 sec. 3.3 and 4.1).
//
// Model: X'_i = R X_i + t, with X_i a point in the previous left-camera frame and X'_i the same
// point in the current one (both from stereo, metres, with 3x3 covariances A_i, A'_i). The
// motion T_cur_prev = [R | t]. Perturbations are on the left: R = exp([dtheta]x) R_hat,
// t = t_hat + dt; the 6x6 covariance is ordered [dtheta (rad), dt (m)].
//
// 1. Points whose 3D uncertainty sqrt(trace(A)) or sqrt(trace(A')) exceeds max_point_sigma_m
//    are discarded.
// 2. Optional seeded RANSAC (3-point Umeyama hypotheses, Mahalanobis inliers) when the set may
//    be badly contaminated.
// 3. Closed form (weighted Umeyama, weights 1 / (trace A + trace A')), then Gauss-Newton on
//    sum r_i^T W_i r_i with r_i = X'_i - (R X_i + t), W_i = (A'_i + R A_i R^T)^-1.
// 4. Outlier loop (seed 001 sec. 3.3): estimate, reject points whose residual (Mahalanobis
//    distance) exceeds k times the mean residual (and reject_floor), k from k_start down to 3.
// 5. Covariance by propagating the point covariances through the cost (Haralick):
//    P_u = H^-1 (sum J_i^T W_i C_i W_i J_i) H^-T, H = sum J_i^T W_i J_i, C_i = A'_i + R A_i R^T,
//    J_i = dr_i/du = [ [R X_i]x , -I ].
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/status.hpp"

namespace svslam {

struct PointPair {
  Eigen::Vector3d p_prev;  // metres, previous camera frame
  Eigen::Matrix3d cov_prev;
  Eigen::Vector3d p_cur;  // metres, current camera frame
  Eigen::Matrix3d cov_cur;
};

struct VisualMotionParams {
  double max_point_sigma_m = 1.0;    // points less precise than this are not used, m, > 0
  int gauss_newton_iterations = 10;  // per estimate, >= 1
  int k_start = 6;                   // outlier loop: k from k_start down to 3, >= 3
  double reject_floor = 1.0;    // residuals (Mahalanobis distance) below this are never rejected,
                                // so a near-perfect fit keeps its points, >= 0
  int min_inliers = 6;          // fewer left -> failure, >= 3
  bool ransac = false;          // seeded RANSAC before the estimation
  int ransac_iterations = 200;  // >= 1
  double ransac_chi2 = 16.27;   // Mahalanobis^2 inlier threshold (chi2 3 dof, 99.9 %)
  std::uint64_t seed = 1;       // RANSAC random generator seed
  Status validate() const;
};

struct VisualMotionResult {
  Eigen::Isometry3d T_cur_prev = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();  // [rot, trans]
  std::vector<std::uint8_t> inlier;  // per input pair
  int used = 0;                      // inliers of the final estimate
  double rms_mahalanobis = 0;        // of the inliers
};

class VisualMotion {
 public:
  explicit VisualMotion(const VisualMotionParams& params);
  const Status& initStatus() const { return init_status_; }
  // Estimates the motion; returns failedPrecondition when too few points survive.
  Status process(const std::vector<PointPair>& pairs, VisualMotionResult& out);

 private:
  VisualMotionParams params_;
  Status init_status_;
  std::vector<int> active_;
  std::vector<double> weight_;
  // Scratch kept across calls (no allocation per frame once grown).
  std::vector<int> sample_, inliers_, kept_;
  std::vector<double> residuals_;
};

// Exponential map of a rotation vector (rad) and its inverse.
Eigen::Matrix3d expSO3(const Eigen::Vector3d& w);
Eigen::Vector3d logSO3(const Eigen::Matrix3d& R);

}  // namespace svslam

#pragma once
// Input checks and small matrix helpers of the EKF (slam/ekf_slam.cpp): covariances must be
// finite, symmetric and positive (semi-)definite, poses rigid; messages are built only on
// failure.
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <string>
#include <string_view>

#include "core/status.hpp"

namespace svslam::ekf_checks {


// What is wrong with a covariance, if anything: it must be finite, symmetric (relative tolerance
// 1e-9) and positive semi-definite (definite when `definite`).
enum class CovarianceFault { kNone, kNonFinite, kAsymmetric, kNotPositive };

template <int N>
CovarianceFault covarianceFault(const Eigen::Matrix<double, N, N>& C, bool definite) {
  if (!C.allFinite()) return CovarianceFault::kNonFinite;
  const double scale = C.cwiseAbs().maxCoeff();
  if ((C - C.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return CovarianceFault::kAsymmetric;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(C, Eigen::EigenvaluesOnly);
  const double min_eig = es.eigenvalues()(0);
  if (definite ? !(min_eig > 0) : min_eig < -1e-12 * scale) return CovarianceFault::kNotPositive;
  return CovarianceFault::kNone;
}

// covarianceFault with a message naming `what` (the message is built only on failure).
template <int N>
Status checkCovariance(const Eigen::Matrix<double, N, N>& C, bool definite, std::string_view what) {
  const char* problem = nullptr;
  switch (covarianceFault<N>(C, definite)) {
    case CovarianceFault::kNone:
      return Status::ok();
    case CovarianceFault::kNonFinite:
      problem = " has non-finite entries";
      break;
    case CovarianceFault::kAsymmetric:
      problem = " is not symmetric";
      break;
    case CovarianceFault::kNotPositive:
      problem = definite ? " is not positive definite" : " is not positive semi-definite";
      break;
  }
  return Status::invalidArgument(std::string(what) + problem);
}

// M <- (M + M^T) / 2 for a square M: exactly symmetric.
inline void symmetrise(Eigen::Ref<Eigen::MatrixXd> M) {
  for (Eigen::Index c = 0; c < M.cols(); ++c)
    for (Eigen::Index r = c + 1; r < M.rows(); ++r) M(r, c) = M(c, r) = 0.5 * (M(r, c) + M(c, r));
}

inline Status checkRigid(const Eigen::Isometry3d& T, std::string_view what) {
  if (!T.matrix().allFinite())
    return Status::invalidArgument(std::string(what) + " has non-finite entries");
  const Eigen::Matrix3d& R = T.linear();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      R.determinant() < 0)
    return Status::invalidArgument(std::string(what) + " rotation is not a rotation matrix");
  return Status::ok();
}

// Re-orthonormalises a rotation that accumulated round-off.
inline Eigen::Matrix3d orthonormalised(const Eigen::Matrix3d& R) {
  return Eigen::Quaterniond(R).normalized().toRotationMatrix();
}

}  // namespace svslam::ekf_checks

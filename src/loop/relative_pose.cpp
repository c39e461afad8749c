#include "loop/relative_pose.hpp"

#include <Eigen/Cholesky>
#include <cmath>

namespace svslam {

Vector6d relativePoseResidual(const Eigen::Isometry3d& T_world_a,
                              const Eigen::Isometry3d& T_world_b, const Eigen::Isometry3d& Z_a_b) {
  return boxMinus(T_world_a.inverse(Eigen::Isometry) * T_world_b, Z_a_b);
}

Matrix6d inverseJacobian(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d Rt = T.linear().transpose();
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = -Rt;
  J.bottomLeftCorner<3, 3>() = -Rt * hatSO3(T.translation());
  J.bottomRightCorner<3, 3>() = -Rt;
  return J;
}

Eigen::Isometry3d productJacobians(const std::vector<Eigen::Isometry3d>& factors,
                                   std::vector<Matrix6d>& A) {
  const std::size_t n = factors.size();
  A.resize(n);
  // prefix[k] = T_1 ... T_k (prefix[0] = identity).
  std::vector<Eigen::Isometry3d> prefix(n + 1, Eigen::Isometry3d::Identity());
  for (std::size_t k = 0; k < n; ++k) prefix[k + 1] = prefix[k] * factors[k];
  const Eigen::Vector3d t_F = prefix[n].translation();
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Matrix3d R_pre = prefix[k].linear();
    Matrix6d& Ak = A[k];
    Ak.setZero();
    Ak.topLeftCorner<3, 3>() = R_pre;
    Ak.bottomLeftCorner<3, 3>() = -hatSO3(t_F - prefix[k + 1].translation()) * R_pre;
    Ak.bottomRightCorner<3, 3>() = R_pre;
  }
  return prefix[n];
}

bool isValidCovariance(const Matrix6d& C) {
  if (!C.allFinite()) return false;
  const double scale = C.cwiseAbs().maxCoeff();
  if (!(scale > 0)) return false;
  if ((C - C.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return false;
  const Eigen::LLT<Matrix6d> llt(C);
  if (llt.info() != Eigen::Success) return false;
  return llt.matrixL().toDenseMatrix().diagonal().minCoeff() > 0;
}

bool isValidPose(const Eigen::Isometry3d& T) {
  if (!T.matrix().allFinite()) return false;
  const Eigen::Matrix3d R = T.linear();
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 &&
         R.determinant() > 0;
}

}  // namespace svslam

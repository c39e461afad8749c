#include "slam/pose_jacobians.hpp"

#include "motion/visual_motion.hpp"

namespace svslam {

Eigen::Isometry3d boxPlus(const Eigen::Isometry3d& T_hat, const Vector6d& d) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = expSO3(d.head<3>()) * T_hat.linear();
  T.translation() = T_hat.translation() + d.tail<3>();
  return T;
}

Vector6d boxMinus(const Eigen::Isometry3d& T, const Eigen::Isometry3d& T_hat) {
  Vector6d d;
  d.head<3>() = logSO3(T.linear() * T_hat.linear().transpose());
  d.tail<3>() = T.translation() - T_hat.translation();
  return d;
}

Matrix6d cameraFrameCovariance(const Eigen::Isometry3d& T_world_cam, const Matrix6d& P_world) {
  Matrix6d B = Matrix6d::Zero();
  B.topLeftCorner<3, 3>() = T_world_cam.linear();
  B.bottomRightCorner<3, 3>() = T_world_cam.linear();
  Matrix6d P = B.transpose() * P_world * B;
  return 0.5 * (P + P.transpose());
}

Eigen::Isometry3d predictPose(const Eigen::Isometry3d& T_world_cam,
                              const Eigen::Isometry3d& T_cur_prev) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = T_world_cam.linear() * T_cur_prev.linear().transpose();
  T.translation() = T_world_cam.translation() - T.linear() * T_cur_prev.translation();
  return T;
}

void predictionJacobians(const Eigen::Isometry3d& T_world_cam, const Eigen::Isometry3d& T_cur_prev,
                         Matrix6d& F_x, Matrix6d& F_u) {
  const Eigen::Matrix3d R_new = T_world_cam.linear() * T_cur_prev.linear().transpose();
  const Eigen::Vector3d& t_u = T_cur_prev.translation();
  F_x.setIdentity();
  F_x.block<3, 3>(3, 0) = hatSO3(R_new * t_u);
  F_u.setZero();
  F_u.block<3, 3>(0, 0) = -R_new;
  F_u.block<3, 3>(3, 0) = -R_new * hatSO3(t_u);
  F_u.block<3, 3>(3, 3) = -R_new;
}

Eigen::Vector3d observeLandmark(const Eigen::Isometry3d& T_world_cam,
                                const Eigen::Vector3d& m_world) {
  return T_world_cam.linear().transpose() * (m_world - T_world_cam.translation());
}

void observationJacobians(const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& m_world,
                          Matrix36d& H_pose, Eigen::Matrix3d& H_m) {
  const Eigen::Matrix3d Rt = T_world_cam.linear().transpose();
  H_pose.leftCols<3>() = Rt * hatSO3(m_world - T_world_cam.translation());
  H_pose.rightCols<3>() = -Rt;
  H_m = Rt;
}

Eigen::Vector3d initLandmark(const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& z_cam) {
  return T_world_cam.linear() * z_cam + T_world_cam.translation();
}

void initJacobians(const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& z_cam,
                   Matrix36d& G_x, Eigen::Matrix3d& G_z) {
  G_x.leftCols<3>() = -hatSO3(T_world_cam.linear() * z_cam);
  G_x.rightCols<3>().setIdentity();
  G_z = T_world_cam.linear();
}

}  // namespace svslam

#include "slam/drift_consider.hpp"

#include <cmath>

#include "core/so3.hpp"

namespace svslam {

Status DriftConsiderParams::validate() const {
  if (!std::isfinite(sigma_rotation_rad_per_m) || sigma_rotation_rad_per_m < 0.0 ||
      sigma_rotation_rad_per_m > 0.1)
    return Status::invalidArgument("drift_sigma_rotation_rad_per_m must be in 0..0.1 rad/m");
  return Status::ok();
}

DriftConsider::DriftConsider(const DriftConsiderParams& params)
    : params_(params), init_status_(params.validate()) {}

Status DriftConsider::process(const Eigen::Isometry3d& T_world_origin,
                              const Eigen::Isometry3d& T_world_cam,
                              Eigen::Matrix<double, 6, 6>& cov) {
  cov.setZero();
  if (!init_status_) return init_status_;
  if (!T_world_origin.matrix().allFinite() || !T_world_cam.matrix().allFinite())
    return Status::invalidArgument("drift consider: non-finite pose");
  if (!params_.active()) return Status::ok();
  const Eigen::Isometry3d T_origin_cam = T_world_origin.inverse() * T_world_cam;
  if (!started_ || T_world_origin.matrix() != T_world_origin_.matrix()) {
    started_ = true;
    T_world_origin_ = T_world_origin;
    J_phi_.setZero();
    J_e_.setZero();
  } else {
    const Eigen::Matrix3d& R_prev = T_origin_prev_.linear();
    const Eigen::Vector3d dt = T_origin_prev_.inverse() * T_origin_cam.translation();
    J_e_ -= hatSO3(R_prev * dt) * J_phi_;
    J_phi_ += dt.norm() * R_prev;
  }
  T_origin_prev_ = T_origin_cam;
  const Eigen::Matrix3d& R_wo = T_world_origin.linear();
  Eigen::Matrix<double, 6, 3> J;
  J.topRows<3>() = R_wo * J_phi_;
  J.bottomRows<3>() = R_wo * J_e_;
  const double var = params_.sigma_rotation_rad_per_m * params_.sigma_rotation_rad_per_m;
  cov = var * J * J.transpose();
  cov = 0.5 * (cov + cov.transpose()).eval();
  return Status::ok();
}

}  // namespace svslam

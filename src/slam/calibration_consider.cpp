#include "slam/calibration_consider.hpp"

#include <cmath>
#include <string>

#include "core/so3.hpp"

namespace svslam {

Status CalibrationConsiderParams::validate() const {
  if (!std::isfinite(sigma_principal_point_px) || sigma_principal_point_px < 0.0 ||
      sigma_principal_point_px > 100.0)
    return Status::invalidArgument("calibration_sigma_principal_point_px must be in 0..100 px");
  if (!std::isfinite(sigma_scale) || sigma_scale < 0.0 || sigma_scale > 0.5)
    return Status::invalidArgument("calibration_sigma_scale must be in 0..0.5");
  return Status::ok();
}

CalibrationConsider::CalibrationConsider(const CalibrationConsiderParams& params, double f_px)
    : params_(params), f_px_(f_px) {
  init_status_ = params.validate();
  if (init_status_ && !(std::isfinite(f_px) && f_px > 0.0))
    init_status_ = Status::invalidArgument("calibration consider: focal length must be > 0, got " +
                                           std::to_string(f_px));
}

Status CalibrationConsider::process(const Eigen::Isometry3d& T_world_origin,
                                    const Eigen::Isometry3d& T_world_cam,
                                    Eigen::Matrix<double, 6, 6>& cov) const {
  cov.setZero();
  if (!init_status_) return init_status_;
  if (!T_world_origin.matrix().allFinite() || !T_world_cam.matrix().allFinite())
    return Status::invalidArgument("calibration consider: non-finite pose");
  if (!params_.active()) return Status::ok();
  const Eigen::Isometry3d T_oc = T_world_origin.inverse() * T_world_cam;
  const Eigen::Matrix3d R = T_oc.linear();
  const Eigen::Vector3d t = T_oc.translation();
  const Eigen::Matrix3d R_wo = T_world_origin.linear();
  const Eigen::Matrix3d t_x = hatSO3(t);
  // Columns theta_x, theta_y (theta_z has no variance), s.
  Eigen::Matrix<double, 6, 3> J;
  J.topLeftCorner<3, 2>() = (R_wo * (R - Eigen::Matrix3d::Identity())).leftCols<2>();
  J.topRightCorner<3, 1>().setZero();
  J.bottomLeftCorner<3, 2>() = (R_wo * t_x).leftCols<2>();
  J.bottomRightCorner<3, 1>() = R_wo * t;
  const double sigma_theta = params_.sigma_principal_point_px / f_px_;
  const Eigen::Vector3d var(sigma_theta * sigma_theta, sigma_theta * sigma_theta,
                            params_.sigma_scale * params_.sigma_scale);
  cov = J * var.asDiagonal() * J.transpose();
  cov = 0.5 * (cov + cov.transpose()).eval();
  return Status::ok();
}

}  // namespace svslam

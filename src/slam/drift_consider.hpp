#pragma once
// The pose covariance that the odometry's rotational drift adds (a "consider" covariance, like
// slam/calibration_consider.hpp). On real cameras every frame-to-frame rotation carries a small
// error that does not average out (shared calibration, rectification and scene errors: on
// kitti_odometry_seq_a a roll of 17-28 mdeg a frame, docs/slam.md); the filter cannot tell it
// from the motion, so its covariance shrinks as if the errors were independent while the
// attitude error, and the position error it makes, grow with the path. The KITTI devkit
// measures this drift as a rotation error per metre travelled (r_err, deg/m).
//
// Model. An unknown constant rotation rate b (rad per metre, camera axes, each axis with
// standard deviation sigma) turns every step: the estimated step k (relative motion from
// camera k-1 to camera k, translation dt_k) is exp([|dt_k| b]x) dR_k. O is the frame the
// trajectory starts in (T_world_origin, exact), R_{k-1} the rotation of camera k-1 in O. With
// the filter's convention (left perturbation, [dtheta, dt]) the errors of pose k are
//   phi_k = phi_{k-1} + |dt_k| R_{k-1} b                  (attitude, frame O)
//   e_k   = e_{k-1} + phi_{k-1} x (R_{k-1} dt_k)           (position, frame O)
// so, to first order, [phi; e] = J b with
//   J_phi,k = J_phi,k-1 + |dt_k| R_{k-1}
//   J_e,k   = J_e,k-1 - [R_{k-1} dt_k]x J_phi,k-1
// and the covariance in the world frame is sigma^2 (blkdiag(R_wo, R_wo) J)(...)^T. A bias
// grows linearly with the path (the variance as its square), unlike the filter's random walk.
// The steps are the published poses' (the filter's estimate); the model restarts whenever
// the origin changes (a new map).
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/status.hpp"

namespace svslam {

struct DriftConsiderParams {
  // Standard deviation of the rotation drift rate about each camera axis, rad per metre
  // travelled, >= 0 (0 = off). The KITTI devkit's r_err (deg/m, the norm over the three
  // axes) is about sqrt(3) * sigma in those units.
  double sigma_rotation_rad_per_m = 0.0;
  Status validate() const;
  bool active() const { return sigma_rotation_rad_per_m > 0.0; }
};

class DriftConsider {
 public:
  explicit DriftConsider(const DriftConsiderParams& params);
  const Status& initStatus() const { return init_status_; }
  // Adds the step from the previous call's pose to T_world_cam and writes the covariance
  // ([dtheta rad, dt m], world frame, symmetric PSD) of the trajectory started at
  // T_world_origin. A different origin than the previous call's restarts the model (zero at
  // its first pose). invalidArgument for non-finite poses (cov zeroed, state kept).
  Status process(const Eigen::Isometry3d& T_world_origin, const Eigen::Isometry3d& T_world_cam,
                 Eigen::Matrix<double, 6, 6>& cov);

 private:
  DriftConsiderParams params_;
  Status init_status_;
  bool started_ = false;
  Eigen::Isometry3d T_world_origin_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_origin_prev_ = Eigen::Isometry3d::Identity();  // last pose, frame O
  Eigen::Matrix3d J_phi_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d J_e_ = Eigen::Matrix3d::Zero();
};

}  // namespace svslam

#pragma once
// The pose covariance that the stereo rig's calibration errors add (a "consider" covariance:
// parameters the filter does not estimate, whose uncertainty is carried into what it
// publishes). The filter's own covariance sees the random errors of the images; a calibration
// error is the same in every frame, so the error it makes grows with the path while the
// filter's covariance does not see it (docs/slam.md "Calibration uncertainty").
//
// Model. O is the frame the trajectory starts in (the first pose, or the pose of the last
// reset: exact, T_world_origin), C the current left camera, T_origin_cam = (R, t).
//  - A principal-point error (dcx, dcy) px makes the camera frame the filter works in a rotation
//    Q = exp([theta]x) of the physical one, theta = (-dcy / f, dcx / f, 0) rad (a pixel shift
//    is a rotation of every bearing about the optical centre, to first order near the axis; a
//    bearing x = X / Z off it turns by theta / (1 + x^2)). Every relative motion is then
//    estimated as Q^T T Q: R^ = Q^T R Q, t^ = Q^T t.
//  - A depth-scale error s (baseline, focal length, the disparity offset left after its online
//    estimate) scales every stereo point, so every translation: t^ = (1 + s) Q^T t.
// To first order, with the filter's convention (left perturbation, [dtheta, dt]):
//   R^ = exp(phi) R,   phi = Q^T R Q R^T -> (R - I) theta
//   t^ - t = s t - [theta]x t = [t]x theta + s t
// and in the world frame (R_wo = rotation of T_world_origin):
//   J = [ R_wo (R - I)   0        ]   columns theta_x, theta_y, theta_z, s
//       [ R_wo [t]x      R_wo t   ]
//   cov = J diag(sigma_theta^2, sigma_theta^2, 0, sigma_s^2) J^T,  sigma_theta = sigma_pp / f.
// It grows with the distance from the origin (translation) and with the rotation away from the
// origin's attitude (attitude); a rotation about the origin's optical axis is not made by the
// principal point, so theta_z has no variance. Zero at the origin.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/status.hpp"

namespace svslam {

struct CalibrationConsiderParams {
  // Standard deviation of the left camera's principal point (cx and cy each), px, >= 0: what
  // the calibration's own uncertainty is (svslam calibrate reports it). 0 = exact.
  double sigma_principal_point_px = 0.0;
  // Relative standard deviation of the stereo depth scale (baseline, focal length, residual
  // disparity offset), >= 0, e.g. 0.002 = 0.2 %. 0 = exact.
  double sigma_scale = 0.0;
  Status validate() const;
  bool active() const { return sigma_principal_point_px > 0.0 || sigma_scale > 0.0; }
};

class CalibrationConsider {
 public:
  // f_px: the left camera's focal length (> 0, finite).
  CalibrationConsider(const CalibrationConsiderParams& params, double f_px);
  const Status& initStatus() const { return init_status_; }
  // cov ([dtheta rad, dt m], world frame, symmetric PSD) for the current pose T_world_cam of a
  // trajectory started at T_world_origin. invalidArgument for non-finite poses (cov zeroed).
  Status process(const Eigen::Isometry3d& T_world_origin, const Eigen::Isometry3d& T_world_cam,
                 Eigen::Matrix<double, 6, 6>& cov) const;

 private:
  CalibrationConsiderParams params_;
  double f_px_;
  Status init_status_;
};

}  // namespace svslam

#pragma once
// Pose composition, landmark models and their analytic Jacobians for the EKF SLAM of seed 001
// section 4, in the error-state convention of the filter.
//
// Frames and units: T_world_cam maps points of the left camera frame (x right, y down,
// z forward, metres) into the world frame; T_cur_prev (the VME result) maps points of the
// previous camera frame into the current one.
//
// Error state (the same left perturbation as the VME, src/motion/visual_motion.hpp): a pose
// T = [R | t] is the estimate T^ = [R^ | t^] perturbed by d = [dtheta (rad), dt (m)] as
//     R = exp([dtheta]x) R^,   t = t^ + dt            (written T = boxPlus(T^, d)).
// dtheta is a small rotation about the axes of the frame the pose maps INTO (the world frame for
// T_world_cam, the current camera frame for T_cur_prev). [v]x is the skew matrix, [v]x w = v x w.
//
// Models and Jacobians (derived to first order in the errors; tested against numerical
// differentiation in tests/slam/ekf_slam_test.cpp):
//  Prediction (seed 001 sec 4, eq. 1): T_new = T_world_cam * T_cur_prev^-1, i.e. with
//  u = [R_u | t_u]
//     R_new = R R_u^T,   t_new = t - R_new t_u.
//   new pose error = F_x * old pose error + F_u * motion error, with a = R_new t_u:
//     F_x = [ I      0 ]        F_u = [ -R_new            0      ]
//           [ [a]x   I ]              [ -R_new [t_u]x    -R_new  ]
//  Observation of landmark m (world, m): z = h(T, m) = R^T (m - t)  (camera frame, m):
//     dz = H_pose [dtheta; dt] + H_m dm,  H_pose = [ R^T [m - t]x , -R^T ],  H_m = R^T.
//  Landmark initialisation (seed 001 sec 4, eq. 4): m = g(T, z) = R z + t:
//     dm = G_x [dtheta; dt] + G_z dz,     G_x = [ -[R z]x , I ],           G_z = R.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/so3.hpp"  // hatSO3

namespace svslam {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix36d = Eigen::Matrix<double, 3, 6>;

// T = boxPlus(T_hat, d) = [exp([d.head<3>()]x) R_hat | t_hat + d.tail<3>()].
Eigen::Isometry3d boxPlus(const Eigen::Isometry3d& T_hat, const Vector6d& d);
// The inverse: d = [log(R R_hat^T), t - t_hat] so that boxPlus(T_hat, d) == T.
Vector6d boxMinus(const Eigen::Isometry3d& T, const Eigen::Isometry3d& T_hat);

// Prediction model: T_world_cam_new = T_world_cam * T_cur_prev^-1.
Eigen::Isometry3d predictPose(const Eigen::Isometry3d& T_world_cam,
                              const Eigen::Isometry3d& T_cur_prev);
void predictionJacobians(const Eigen::Isometry3d& T_world_cam, const Eigen::Isometry3d& T_cur_prev,
                         Matrix6d& F_x, Matrix6d& F_u);

// Observation model: landmark m_world (m) seen in the camera of pose T_world_cam.
Eigen::Vector3d observeLandmark(const Eigen::Isometry3d& T_world_cam,
                                const Eigen::Vector3d& m_world);
void observationJacobians(const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& m_world,
                          Matrix36d& H_pose, Eigen::Matrix3d& H_m);

// The covariance of a pose error in the filter's convention (world frame, left: boxPlus) as the
// covariance of the right-multiplied camera-frame error of LCM's pose_t, T = T_hat exp(xi),
// xi = [dtheta_c; rho]: to first order R = R_hat exp([dtheta_c]x) = exp([R_hat dtheta_c]x) R_hat
// and t = t_hat + R_hat rho, so xi = B^T d with B = diag(R_hat, R_hat), and the covariance is
// B^T P_world B.
Matrix6d cameraFrameCovariance(const Eigen::Isometry3d& T_world_cam, const Matrix6d& P_world);

// Initialisation model: the world position of a point z_cam (m) of the camera frame.
Eigen::Vector3d initLandmark(const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& z_cam);
void initJacobians(const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& z_cam,
                   Matrix36d& G_x, Eigen::Matrix3d& G_z);

}  // namespace svslam

#pragma once
// Relative-pose residuals and the first-order Jacobians of composition and inversion, shared by
// the pose graph (loop/pose_graph.hpp) and the loop consistency check (loop/loop_consistency.hpp).
// Pure Eigen.
//
// Convention (the same as src/motion/visual_motion.hpp and src/slam/pose_jacobians.hpp):
// T_a_b maps points of frame b into frame a, p_a = R p_b + t. An uncertain pose is the estimate
// T^ perturbed on the left, d = [dtheta (rad), dt (m)]:
//     R = exp([dtheta]x) R^,   t = t^ + dt          (T = boxPlus(T^, d)),
// so dtheta and dt are expressed in frame a. A 6x6 covariance is ordered [dtheta, dt].
//
// Residual of a measurement Z_a_b against keyframe poses T_world_a, T_world_b:
//     Zhat = T_world_a^-1 T_world_b = (Rhat, that),
//     r = [ log(Rhat R_Z^T) ; that - t_Z ] = boxMinus(Zhat, Z)     (6-vector, zero at truth).
//
// Jacobians (first order, derived from the definitions above, checked numerically in
// tests/loop/relative_pose_test.cpp):
//  Inversion, T' = T^-1:       d' = J_inv d,   J_inv = [ -R^T          0    ]
//                                                      [ -R^T [t]x   -R^T  ]
//  Product F = T_1 T_2 ... T_n with factor k perturbed by d_k:  dF = sum_k A_k d_k,
//      A_k = [ R_<k                     0    ]
//            [ -[t_F - t_<=k]x R_<k    R_<k  ]
//  where R_<k is the rotation of T_1 ... T_(k-1) (identity for k = 1) and t_<=k the translation
//  of T_1 ... T_k. For two factors: A_1 = [I 0; -[R_1 t_2]x I], A_2 = diag(R_1, R_1) (the
//  "adjoint" that transports a perturbation of T_2, expressed in T_2's output frame, into the
//  output frame of T_1).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "slam/pose_jacobians.hpp"

namespace svslam {

// r = boxMinus(T_world_a^-1 T_world_b, Z_a_b), see above.
Vector6d relativePoseResidual(const Eigen::Isometry3d& T_world_a,
                              const Eigen::Isometry3d& T_world_b, const Eigen::Isometry3d& Z_a_b);

// J_inv of the inversion T -> T^-1 (above).
Matrix6d inverseJacobian(const Eigen::Isometry3d& T);

// The Jacobians A_k of the product of `factors` (above); A is resized to factors.size().
// Returns the product.
Eigen::Isometry3d productJacobians(const std::vector<Eigen::Isometry3d>& factors,
                                   std::vector<Matrix6d>& A);

// True when C is finite, symmetric (to 1e-9 relative) and positive definite (Cholesky succeeds).
bool isValidCovariance(const Matrix6d& C);

// True when every entry of T is finite and its rotation is orthonormal to 1e-6.
bool isValidPose(const Eigen::Isometry3d& T);

}  // namespace svslam

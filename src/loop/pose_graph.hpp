#pragma once
// Pose-graph optimisation (Ceres) of keyframe poses T_world_kf from relative-pose edges:
// odometry edges between consecutive keyframes and loop-closure edges.
//
// Each edge measures Z = T_from_to (maps points of keyframe `to` into keyframe `from`) with a 6x6
// covariance C ordered [dtheta (rad), dt (m)] in the left-perturbation convention of
// loop/relative_pose.hpp (R = exp([dtheta]x) R^, t = t^ + dt). Its residual is
//     r = [ log(Rhat R_Z^T) ; that - t_Z ],   (Rhat, that) = T_world_from^-1 T_world_to,
// whitened as w = L^-1 r with C = L L^T (so |w|^2 = r^T C^-1 r, the edge's chi2, 6 dof).
// The cost minimised is 1/2 sum_odometry |w|^2 + 1/2 sum_loops rho(|w|^2), with rho the Cauchy
// loss rho(s) = a^2 log(1 + s / a^2), a = loop_loss_scale (a Mahalanobis distance): a loop whose
// whitened residual is well beyond a has a bounded, vanishing influence. a = 0 turns the robust
// loss off (plain least squares on loop edges as well).
//
// Parameters: per keyframe an Eigen quaternion (x, y, z, w; ceres::EigenQuaternionManifold) and a
// translation (m). The pose `fixed_index` is held constant (gauge). Rotation log via
// ceres::QuaternionToAngleAxis (w, x, y, z order). Linear solver: sparse normal Cholesky
// (SuiteSparse, else Eigen's sparse Cholesky, else Accelerate), falling back to ITERATIVE_SCHUR
// when Ceres was built without a sparse library. One thread by default: bit-identical results
// from run to run.
//
// No clocks here: callers time optimize() themselves.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "loop/relative_pose.hpp"

namespace svslam {

struct PoseGraphParams {
  int max_iterations = 100;  // Levenberg-Marquardt iterations, >= 1
  // Cauchy scale a of the loop edges, in units of whitened residual norm (Mahalanobis
  // distance). sqrt(12.59) = sqrt(chi2_6 at 95 %). 0 = no robust loss. >= 0.
  double loop_loss_scale = 3.5483;
  double function_tolerance = 1e-10;  // Ceres: relative cost decrease to stop, > 0
  int num_threads = 1;                // Ceres threads, >= 1 (1: deterministic)
  Status validate() const;
};

struct PoseGraphEdge {
  int from = 0, to = 0;                                         // keyframe indices, from != to
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();  // measured relative pose
  Matrix6d covariance =
      Matrix6d::Identity();  // [dtheta (rad), dt (m)], symmetric positive definite
  bool loop = false;         // loop-closure edge (robust loss) rather than odometry
};

struct PoseGraphReport {
  int iterations = 0;       // Levenberg-Marquardt steps taken (successful + unsuccessful)
  double initial_cost = 0;  // Ceres cost (1/2 sum of rho(|w|^2)) before and after
  double final_cost = 0;
  bool converged = false;         // Ceres stopped on a tolerance (not on max_iterations)
  std::vector<double> loop_chi2;  // per loop edge in input order: |w|^2 after optimisation
  std::string message;            // Ceres' termination message
};

class PoseGraph {
 public:
  explicit PoseGraph(const PoseGraphParams& params);
  const Status& initStatus() const { return init_status_; }
  // Optimises T_world_kf in place (left untouched on failure). invalidArgument when: no pose or
  // no edge; fixed_index or an edge index out of range; from == to; a pose not finite or not a
  // rotation; a covariance not finite, symmetric and positive definite; a pose not connected to
  // fixed_index through the edges (its gauge would be free). internal when Ceres fails.
  // first_free > 0: the poses before it are held constant as well (a window solve: only the
  // newest keyframes move, the loops into older ones pull them against a fixed past) and edges
  // between two constant poses are left out, so the cost grows with n - first_free, not n.
  Status optimize(std::vector<Eigen::Isometry3d>& T_world_kf,
                  const std::vector<PoseGraphEdge>& edges, int fixed_index,
                  PoseGraphReport& report, int first_free = 0);

 private:
  PoseGraphParams params_;
  Status init_status_;
  std::vector<double> quaternions_;   // 4 per keyframe, Eigen order (x, y, z, w)
  std::vector<double> translations_;  // 3 per keyframe, m
};

}  // namespace svslam

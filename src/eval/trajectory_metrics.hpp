#pragma once
// Trajectory accuracy: KITTI-devkit segment drift, ATE after SE(3) Umeyama alignment, RPE per
// frame, final position and attitude errors.
//
// Inputs are associated pose pairs (gt[k], est[k]) of the same camera (T_world_cam: maps a point
// in the camera frame into the trajectory's world frame, metres). Each trajectory may live in its
// own world frame: drift and RPE use relative motions only; ATE and the final errors compare
// positions after SE(3) alignment (Umeyama, no scale), after Sim(3) alignment (Umeyama with
// scale: for an estimate up to scale, e.g. monocular) or, with align = kNone, after expressing
// both trajectories relative to their first pose.
#include <Eigen/Geometry>
#include <vector>

#include "core/status.hpp"

namespace svslam {

enum class TrajectoryAlignment { kSe3, kSim3, kNone };

struct SegmentDrift {
  double length_m = 0;
  int count = 0;               // segments of this length found
  double t_err_pct = 0;        // mean |translation error| / length, percent
  double r_err_deg_per_m = 0;  // mean rotation error / length
};

struct TrajectoryMetrics {
  int frames = 0;
  std::vector<SegmentDrift> segments;
  double t_err_pct = 0;  // mean over every segment of every length (devkit average)
  double r_err_deg_per_m = 0;
  double ate_rmse_m = 0;
  double rpe_trans_rmse_m = 0;  // frame-to-frame relative pose error
  double rpe_rot_rmse_deg = 0;
  double final_pos_err_m = 0;
  double final_att_err_deg = 0;  // of the last pose relative to the first (alignment-free)
  double path_length_m = 0;  // ground truth
  double align_scale = 1;    // the Sim(3) alignment's scale (1 for the other alignments)
  // A rotation of the whole estimate about its first camera centre: with both trajectories
  // relative to their first pose (p_i = positions, whatever the alignment), the rotation Q
  // minimising sum |g_i - Q e_i|^2 (orthogonal Procrustes about the origin, Kabsch: SVD of
  // sum g_i e_i^T). It is the error a global attitude offset makes (the start's attitude drifted
  // before the trajectory's shape was fixed, a tilted plane of a loop), which relative
  // constraints such as loop closures cannot see; what remains after it is the shape's error.
  double start_rotation_deg = 0;             // angle of Q
  Eigen::Vector3d start_rotation_axis = Eigen::Vector3d::UnitZ();  // unit, first camera frame
  double ate_after_start_rotation_m = 0;     // RMS |g_i - Q e_i|
  double final_pos_err_after_start_rotation_m = 0;
};

struct TrajectoryEvalParams {
  std::vector<double> segment_lengths_m = {100, 200, 300, 400, 500, 600, 700, 800};  // devkit
  int step_frames = 10;  // first frames of segments every step_frames frames (devkit: 10)
  TrajectoryAlignment align = TrajectoryAlignment::kSe3;
  Status validate() const;
};

// The rigid transform T (no scale) minimising sum |gt_i - T est_i|^2 (Umeyama 1991).
// Precondition: equal sizes >= 3, points not all collinear for a unique answer.
Eigen::Isometry3d umeyamaSe3(const std::vector<Eigen::Vector3d>& est,
                             const std::vector<Eigen::Vector3d>& gt);

// The similarity (s, T) minimising sum |gt_i - (s R est_i + t)|^2 (Umeyama 1991, eq. 40-42):
// with U D V^T the SVD of the cross-covariance and S the reflection guard,
// s = tr(D S) / var(est); T's translation is mu_gt - s R mu_est. Same precondition.
Eigen::Isometry3d umeyamaSim3(const std::vector<Eigen::Vector3d>& est,
                              const std::vector<Eigen::Vector3d>& gt, double& scale);

// Rotation angle of R (a rotation matrix) in radians, in [0, pi].
double rotationAngle(const Eigen::Matrix3d& R);

Result<TrajectoryMetrics> evaluateTrajectory(const std::vector<Eigen::Isometry3d>& gt,
                                             const std::vector<Eigen::Isometry3d>& est,
                                             const TrajectoryEvalParams& params);

// Consistency of an estimate that comes with pose covariances (seed 001 sec 5.1: "absolute
// errors all bounded by twice the estimated standard deviations"). Both trajectories are taken
// relative to their first pose (the filter starts there with zero covariance). The error of pose
// i, in the filter's error-state convention (left perturbation in the world frame,
// [rot rad, trans m]):
//     e = [log(R_gt R_est^T), t_gt - t_est],   NEES_i = e^T P_i^-1 e  (6 dof).
// Frames whose covariance is not positive definite (the first) are skipped.
struct NeesResult {
  int frames = 0;               // frames evaluated
  double mean_nees = 0;         // expected 6 for a consistent filter
  double mean_nees_position = 0;  // 3-dof NEES of the position alone (expected 3)
  double within_2sigma_pct = 0;   // frames where every one of the 6 |e_k| <= 2 sigma_k
  double position_within_2sigma_pct = 0;  // frames where the 3 position |e_k| <= 2 sigma_k
  std::vector<double> nees;       // per evaluated frame
};
Result<NeesResult> evaluateNees(const std::vector<Eigen::Isometry3d>& gt,
                                const std::vector<Eigen::Isometry3d>& est,
                                const std::vector<Eigen::Matrix<double, 6, 6>>& cov);

}  // namespace svslam

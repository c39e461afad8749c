#pragma once
// EKF SLAM core of seed 001 section 4: the stereo-bench pose and a set of 3D landmarks.
//
// State x = [x_p, m_1 .. m_N]. x_p = T_world_cam, the left camera in the world (camera x right,
// y down, z forward; metres); m_i the world coordinates of landmark i (m). Landmarks carry stable
// integer ids (never reused, independent of their place in the state vector).
//
// Attitude: an error state on SO(3) (slam/pose_jacobians.hpp). The true pose is the estimate
// perturbed on the left, in the world frame: R_wc = exp([dtheta]x) R^_wc, t_wc = t^_wc + dt.
// The covariance P, (6 + 3N) x (6 + 3N), is that of the error [dtheta (rad), dt (m), dm_1 (m),
// ..., dm_N (m)]. After each update the error estimate is injected into the nominal state
// (R <- exp([dtheta]x) R, t <- t + dt, m_i <- m_i + dm_i) and P is kept as it is: the reset
// Jacobian of the injection is I + O(|dtheta|), dropped to first order (as the rest of the EKF).
//
// Prediction (seed 001 sec 4, eq. 1) from the VME result u = T_cur_prev with covariance R_u in
// the VME convention (left perturbation, [dtheta_u, dt_u]): T_wc <- T_wc * T_cur_prev^-1,
//     P_pp <- F_x P_pp F_x^T + F_u R_u F_u^T,   P_pm <- F_x P_pm,   P_mm unchanged
// (landmarks stationary, no extra process noise; F_x, F_u in slam/pose_jacobians.hpp).
//
// Observation of landmark i (seed 001 sec 4, eqs. 2-3): z_i = R_wc^T (m_i - t_wc), its position
// in the current camera frame measured by stereo with covariance R_i. Innovation nu = z - h(x),
// H = [H_pose 0 .. H_m 0 ..] (3 x n, sparse), S = H P H^T + R_i. Every observation of a call is
// gated on the Mahalanobis distance d^2 = nu^T S^-1 nu against gate_chi2, all against the state
// before the call (before any update); gated ones are reported and not applied. The accepted
// ones are stacked into one update (in batches of at most max_batch_observations, applied one
// after the other, when there are more): with M = P H^T (n x m), K = M S^-1 (S^-1 formed
// explicitly from the Cholesky factor of S and made exactly symmetric),
//     x <- x (+) K nu,
//     Joseph form: P <- (I - K H) P (I - K H)^T + K R K^T = P - K M^T - M K^T + K S K^T,
// evaluated as P - [K D][M K]^T with D = M - K S (exact for any K; D is the round-off of the
// gain solve), so the cost is O(n m) for M, O(n m^2) for K, O(n^2 m) for the one product and no
// n x n identity or dense H is ever formed. With joseph_form = false the optimal-gain form
// P - B B^T, B = M L^-T (S = L L^T), is used instead: a symmetric rank-m downdate, half the
// flops of the Joseph product, but without its guarantee against a perturbed gain.
// P is stored as its lower triangle only and every update computes the lower triangle of the
// new (symmetric) matrix: the represented P is exactly symmetric by construction. The n x n
// products (K, D and the n x n one, which dominates) run in simd::MatrixKernels::rankUpdate
// (fused multiply-adds in a fixed order, AVX2/NEON chosen at run time, bit-exact with the scalar
// reference, so the filter gives the same bits on every backend); on a CPU without hardware FMA,
// Eigen's products instead.
//
// Landmark initialisation (seed 001 sec 4, eqs. 4-5): m = g(x_p, z) = R_wc z + t_wc,
//     P_mm = G_x P_pp G_x^T + G_z R_z G_z^T,   P_m,x = G_x [P_pp P_p,m_1 .. P_p,m_N].
// Removal (retirement) deletes the landmark's rows and columns (the last landmark takes its
// place in the state) and returns its final position and 3x3 covariance.
//
// Storage: P for max_landmarks is allocated in the constructor (the state works on its
// top-left stateDim() block, so adding a landmark never reallocates); predict, update (up to
// max_batch_observations per batch), addLandmark and removeLandmark allocate nothing once
// `results` has reached its size (the id -> slot table holds max_landmarks; the products run in the
// matrix kernels on preallocated workspaces; without hardware FMA, Eigen's products may take
// their blocking workspace from the heap for large operands).
// Inputs are checked before anything changes: non-finite values, non-rotations, covariances
// that are not symmetric positive (semi-)definite and unknown ids are rejected with a Status
// naming the problem, and the filter is left untouched. A numerical failure inside an update
// (innovation covariance not positive definite, non-finite gain) returns kInternal before the
// failing batch touches the state (earlier batches of the same call stay applied).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "core/executor.hpp"
#include "core/status.hpp"
#include "simd/matrix_kernels.hpp"
#include "slam/id_slot_map.hpp"
#include "slam/pose_jacobians.hpp"

namespace svslam {

struct EkfSlamParams {
  // Cost of an update with k observations in batches of b, n = 6 + 3 N (N landmarks), m = 3 b:
  // per batch n^2 m (the n x n product, lower triangle of a rank-2m update) + 2 n m^2 (gain and
  // its round-off D) + O(m^3), i.e. 3 k (n^2 + 2 n m) multiply-adds in all: the state size, not
  // the batch, sets the cost, and small batches avoid the n m^2 terms. The defaults (140
  // landmarks, batches of 16) with the SLAM's 60 observations a frame cost about 40M
  // multiply-adds, half of 300 landmarks observed 30 times (bench/bench_ekf measures both).
  int max_landmarks = 140;          // landmarks in the state at once, [1, 3000]; P storage of
                                    // (6 + 3 max)^2 doubles is preallocated (140: 1.5 MB)
  int max_batch_observations = 16;  // observations stacked in one update, [1, 1000]; more
                                    // accepted observations are applied in successive batches
  double gate_chi2 = 11.34;         // Mahalanobis d^2 threshold, chi-square with 3 dof
                                    // (11.34: 99 %, 7.81: 95 %, 16.27: 99.9 %), > 0
  double bearing_gate_chi2 = 9.21;  // the same for bearings, chi-square with 2 dof (99 %), > 0
  double bearing_min_depth_m = 0.05;  // a bearing whose landmark is predicted nearer than this
                                      // in front of the camera (or behind it) is not applied
  bool joseph_form = true;   // Joseph-form covariance update; false: optimal-gain form P - B B^T
  int max_update_tasks = 2;  // row pieces the update's products are split into on the executor
                             // given to update(), [1, 16]; each piece has its own preallocated
                             // workspace of (2 n_max + 32) 2 m_max doubles (140 landmarks and
                             // batches of 16: 0.7 MB). Results do not depend on it.
  Status validate() const;
};

struct LandmarkObservation {
  int id = -1;            // landmark id returned by addLandmark
  Eigen::Vector3d z_cam;  // measured position in the current left camera frame, m
  Eigen::Matrix3d R;      // its covariance, m^2, symmetric positive definite
};

// Bearing of landmark id (seed 000 part 2, seed 003): its direction in the current left camera
// frame as normalised image coordinates xy = (x / z, y / z) of z_cam = R_wc^T (m - t_wc), with
// covariance R (dimensionless^2; a pixel error sigma_px with focal length f_px gives
// (sigma_px / f_px)^2 I). The model: xy = pi(h(x)), pi(p) = (p_x / p_z, p_y / p_z), so
// H = J_pi [H_pose H_m] with J_pi = [1/z 0 -x/z^2; 0 1/z -y/z^2] at the predicted point.
struct BearingObservation {
  int id = -1;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  Eigen::Matrix2d R = Eigen::Matrix2d::Identity();  // symmetric positive definite
};

struct ObservationResult {
  int id = -1;
  bool accepted = false;      // false: gated out (d^2 > gate_chi2), not applied
  double mahalanobis_d2 = 0;  // nu^T S^-1 nu against the state before the update
};

class EkfSlam {
 public:
  // Validates the parameters and preallocates every workspace. The filter starts at the world
  // origin with a zero covariance and no landmark.
  explicit EkfSlam(const EkfSlamParams& params);
  const Status& initStatus() const { return init_status_; }

  // Restarts at T_world_cam with pose covariance P0 ([dtheta, dt], symmetric positive
  // semi-definite) and no landmark. Landmark ids keep increasing across resets.
  Status reset(const Eigen::Isometry3d& T_world_cam, const Matrix6d& P0);
  // Prediction with the VME result T_cur_prev and its covariance R_u ([dtheta_u, dt_u], VME
  // convention, symmetric positive semi-definite).
  Status predict(const Eigen::Isometry3d& T_cur_prev, const Matrix6d& R_u);
  // Gates and applies the observations of one frame; results[k] describes obs[k]. The products
  // run as row pieces on `executor` when given (bit-identical results for any executor).
  Status update(const std::vector<LandmarkObservation>& obs,
                std::vector<ObservationResult>& results, Executor* executor = nullptr);
  // Gates and applies the bearing observations of one frame (BearingObservation), like
  // update(): gating on bearing_gate_chi2 against the state before the call, stacked 2-row
  // blocks in batches of max_batch_observations, the same gain and covariance forms. A bearing
  // whose landmark is predicted behind the camera or nearer than bearing_min_depth_m is
  // reported not accepted with d^2 = infinity.
  Status updateBearings(const std::vector<BearingObservation>& obs,
                        std::vector<ObservationResult>& results, Executor* executor = nullptr);
  // Adds the landmark measured at z_cam (current camera frame, m) with covariance R_z (m^2,
  // symmetric positive semi-definite); returns its id. failedPrecondition when the state is full.
  Result<int> addLandmark(const Eigen::Vector3d& z_cam, const Eigen::Matrix3d& R_z);
  // Adds a landmark measured at z_cam (m, covariance R_z) from the exactly known pose
  // T_world_cam_exact (no uncertainty, e.g. the first frame, which defines the world frame) by a
  // measurement independent of the state: eqs. (4)-(5) with P_pose = 0, so m = T z,
  // P_mm = R R_z R^T and every cross covariance P_m,x = 0.
  Result<int> addLandmarkFromExactPose(const Eigen::Isometry3d& T_world_cam_exact,
                                       const Eigen::Vector3d& z_cam, const Eigen::Matrix3d& R_z);
  // Puts a removed landmark back into the state under its id, at m_world (m) with covariance
  // cov (m^2) and no cross covariance with the rest of the state: the correlations dropped by
  // removeLandmark are not restored (see slam_system.hpp step 5 for what that assumes).
  // notFound when `id` was never added, failedPrecondition when it is in the state or the
  // state is full.
  Status restoreLandmark(int id, const Eigen::Vector3d& m_world, const Eigen::Matrix3d& cov);
  // Removes landmark `id` from the state; its final position and covariance go to m_world and
  // cov when they are not null.
  Status removeLandmark(int id, Eigen::Vector3d* m_world, Eigen::Matrix3d* cov);
  // Moves the whole state into another world frame (e.g. the loop-closing back end's corrected
  // frame): with C = (R_c, t_c), T_wc <- C T_wc, m_i <- R_c m_i + t_c. The errors rotate with
  // the frame (dtheta' = R_c dtheta, dt' = R_c dt, dm_i' = R_c dm_i), so P <- J P J^T with
  // J = diag(R_c, R_c, R_c, ...): every 3x3 block B_ij <- R_c B_ij R_c^T. A rigid move of the
  // estimate and its uncertainty together: every relative quantity (landmark in the camera,
  // its predicted observation and innovation covariance) is unchanged. O(n^2); allocates nothing.
  Status transformWorld(const Eigen::Isometry3d& C_new_old);
  // Relocalisation (slam/relocaliser.hpp): the pose becomes T_world_cam with covariance P_pose
  // ([dtheta, dt], symmetric positive semi-definite), independent of the landmarks (its cross
  // covariances are set to zero): after a loss the prediction carries no information the
  // relocalised pose does not, and the landmarks keep their own estimates. O(n).
  Status replacePose(const Eigen::Isometry3d& T_world_cam, const Matrix6d& P_pose);
  // Update with a direct measurement of the camera position, t_meas (m, world) with covariance
  // R_meas (m^2, symmetric positive definite; e.g. the loop-closing back end's corrected
  // position): z = t_meas - t_wc = H dx + v with H = [0 I3 0 ... 0], so
  //     S = P_tt + R_meas,  K = P[:, t] S^-1,  x <- x (+) K z,  P <- P - K P[t, :]
  // (the Joseph form and the optimal-gain form agree exactly for this K). The attitude and the
  // landmarks move with the position through their cross covariances. d2 (when not null):
  // z^T S^-1 z (3 dof).
  Status updatePosition(const Eigen::Vector3d& t_meas, const Eigen::Matrix3d& R_meas,
                        double* d2 = nullptr);

  const Eigen::Isometry3d& pose() const { return T_world_cam_; }
  Matrix6d poseCovariance() const;  // [dtheta (rad), dt (m)]
  // Position (m) and 3x3 covariance (m^2) of landmark `id`; notFound when it is not in the state.
  Status landmark(int id, Eigen::Vector3d& m_world, Eigen::Matrix3d& cov) const;
  int numLandmarks() const { return static_cast<int>(ids_.size()); }
  const std::vector<int>& landmarkIds() const { return ids_; }  // in state order
  int stateDim() const { return 6 + 3 * numLandmarks(); }
  // The full symmetric covariance, stateDim()^2, in the order [pose, landmarkIds()...].
  // Allocates: for tests and diagnostics.
  Eigen::MatrixXd covariance() const;

 private:
  int slotOf(int id) const;
  // failedPrecondition naming `what` when the state holds max_landmarks landmarks.
  Status checkRoom(const char* what) const;
  // Appends landmark `id` at m_world (m) with covariance cov (m^2) and no cross covariance.
  // Preconditions: checkRoom passed; id is the next new id or a removed one.
  void appendUncorrelated(int id, const Eigen::Vector3d& m_world, const Eigen::Matrix3d& cov);
  // out.topRows(n) = columns [c0, c0 + k) of the full P, from the stored lower triangle.
  void gatherColumns(int c0, int k, Eigen::MatrixXd& out) const;
  Status checkObservations(const std::vector<LandmarkObservation>& obs) const;
  // One stacked update; its products run as row pieces on `executor` when not null.
  Status applyBatch(const std::vector<LandmarkObservation>& obs, const int* idx, int count,
                    Executor* executor);
  Status applyBearingBatch(const std::vector<BearingObservation>& obs, const int* idx, int count,
                           Executor* executor);
  // The accepted entries of `results`, in order, in batches of at most max_batch_observations:
  // apply(indices, count) for each batch; stops at the first failing batch.
  template <class ApplyBatch>
  Status applyAcceptedInBatches(const std::vector<ObservationResult>& results, ApplyBatch apply) {
    const std::size_t batch = static_cast<std::size_t>(params_.max_batch_observations);
    std::size_t k = 0;
    while (k < results.size()) {
      accepted_.clear();
      for (; k < results.size() && accepted_.size() < batch; ++k)
        if (results[k].accepted) accepted_.push_back(static_cast<int>(k));
      if (accepted_.empty()) break;
      if (Status s = apply(accepted_.data(), static_cast<int>(accepted_.size())); !s) return s;
    }
    return Status::ok();
  }
  // The update from the stacked M = P H^T (B_, n x m), innovation nu_ (m) and S_ (m x m,
  // H P H^T + R, not yet symmetrised): gain, state injection and covariance.
  Status applyStacked(int m, Executor* executor);
  // Bearing model at landmark slot s: predicted xy and its Jacobians (false when the landmark
  // is predicted nearer than bearing_min_depth_m).
  bool bearingModel(int s, Eigen::Vector2d& xy, Eigen::Matrix<double, 2, 6>& H_p,
                    Eigen::Matrix<double, 2, 3>& H_m) const;
  void inject(int n);
  // C -= U V^T (only its lower triangle when lower_only), through the matrix kernels.
  void subtractProduct(Eigen::Ref<Eigen::MatrixXd> C, const Eigen::Ref<const Eigen::MatrixXd>& U,
                       const Eigen::Ref<const Eigen::MatrixXd>& V, bool lower_only,
                       Executor* executor);

  EkfSlamParams params_;
  Status init_status_;
  Eigen::Isometry3d T_world_cam_ = Eigen::Isometry3d::Identity();
  Eigen::Matrix3Xd m_world_;     // 3 x max_landmarks, the first numLandmarks() columns used
  Eigen::MatrixXd P_;            // capacity^2; lower triangle of the active stateDim()^2 block
  std::vector<int> ids_;         // id of each state slot
  IdSlotMap slot_of_id_;         // state slot of each id in the state (<= max_landmarks)
  int next_id_ = 0;
  // Workspaces (capacity rows).
  Eigen::MatrixXd P_pose_;   // n x 6, full P columns of the pose
  Eigen::MatrixXd P_lm_;     // n x 3, full P columns of one landmark
  Eigen::MatrixXd A_, B_;    // n x 2m: [K D] and [M K]
  Eigen::MatrixXd S_, L_;    // m x m: innovation covariance and its Cholesky factor
  Eigen::MatrixXd T_;        // m x m: S^-1 (Joseph) or L^-1 (optimal gain)
  Eigen::VectorXd nu_, dx_;  // m, n
  std::vector<int> accepted_;
  const simd::MatrixKernels* rank_update_ = nullptr;  // null: no hardware FMA, Eigen's product
  std::vector<double> rank_update_ws_;  // max_update_tasks pieces of ws_piece_ doubles
  std::size_t ws_piece_ = 0;
};

}  // namespace svslam

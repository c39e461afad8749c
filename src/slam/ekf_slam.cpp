#include "slam/ekf_slam.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <string_view>

#include "motion/visual_motion.hpp"
#include "simd/matrix_kernels.hpp"
#include "slam/ekf_checks.hpp"

namespace svslam {

using Eigen::Lower;
using ekf_checks::checkCovariance;
using ekf_checks::CovarianceFault;
using ekf_checks::covarianceFault;
using ekf_checks::checkRigid;
using ekf_checks::orthonormalised;
using ekf_checks::symmetrise;


Status EkfSlamParams::validate() const {
  if (max_landmarks < 1 || max_landmarks > 3000)
    return Status::invalidArgument("max_landmarks must be in [1, 3000]");
  if (max_batch_observations < 1 || max_batch_observations > 1000)
    return Status::invalidArgument("max_batch_observations must be in [1, 1000]");
  if (max_update_tasks < 1 || max_update_tasks > 16)
    return Status::invalidArgument("max_update_tasks must be in [1, 16]");
  if (!(gate_chi2 > 0) || !std::isfinite(gate_chi2))
    return Status::invalidArgument("gate_chi2 must be finite and > 0");
  if (!(bearing_gate_chi2 > 0) || !std::isfinite(bearing_gate_chi2))
    return Status::invalidArgument("bearing_gate_chi2 must be finite and > 0");
  if (!(bearing_min_depth_m > 0) || !std::isfinite(bearing_min_depth_m))
    return Status::invalidArgument("bearing_min_depth_m must be finite and > 0");
  return Status::ok();
}

EkfSlam::EkfSlam(const EkfSlamParams& params) : params_(params) {
  init_status_ = params_.validate();
  if (!init_status_) return;
  const int cap = 6 + 3 * params_.max_landmarks;
  const int mcap = 3 * params_.max_batch_observations;
  m_world_.setZero(3, params_.max_landmarks);
  P_.setZero(cap, cap);
  P_pose_.setZero(cap, 6);
  P_lm_.setZero(cap, 3);
  A_.setZero(cap, 2 * mcap);
  B_.setZero(cap, 2 * mcap);
  S_.setZero(mcap, mcap);
  L_.setZero(mcap, mcap);
  T_.setZero(mcap, mcap);
  nu_.setZero(mcap);
  dx_.setZero(cap);
  if (simd::matrixKernelsHaveHardwareFma()) {
    rank_update_ = &simd::matrixKernels();
    ws_piece_ = simd::rankUpdateWorkspace(cap, cap, 2 * mcap);
    rank_update_ws_.assign(ws_piece_ * static_cast<std::size_t>(params_.max_update_tasks), 0.0);
  }
  ids_.reserve(static_cast<std::size_t>(params_.max_landmarks));
  slot_of_id_.reserve(params_.max_landmarks);
  accepted_.reserve(static_cast<std::size_t>(params_.max_batch_observations));
}

Status EkfSlam::reset(const Eigen::Isometry3d& T_world_cam, const Matrix6d& P0) {
  if (!init_status_) return init_status_;
  if (Status s = checkRigid(T_world_cam, "reset: T_world_cam"); !s) return s;
  if (Status s = checkCovariance<6>(P0, false, "reset: P0"); !s) return s;
  T_world_cam_ = Eigen::Isometry3d::Identity();
  T_world_cam_.linear() = orthonormalised(T_world_cam.linear());
  T_world_cam_.translation() = T_world_cam.translation();
  slot_of_id_.clear();
  ids_.clear();
  P_.topLeftCorner<6, 6>() = 0.5 * (P0 + P0.transpose());
  return Status::ok();
}

Status EkfSlam::replacePose(const Eigen::Isometry3d& T_world_cam, const Matrix6d& P_pose) {
  if (!init_status_) return init_status_;
  if (Status s = checkRigid(T_world_cam, "replacePose: T_world_cam"); !s) return s;
  if (Status s = checkCovariance<6>(P_pose, false, "replacePose: P_pose"); !s) return s;
  T_world_cam_.linear() = orthonormalised(T_world_cam.linear());
  T_world_cam_.translation() = T_world_cam.translation();
  const int n = stateDim();
  P_.topLeftCorner<6, 6>() = 0.5 * (P_pose + P_pose.transpose());
  // The stored lower triangle: rows of the landmarks, columns of the pose.
  if (n > 6) P_.block(6, 0, n - 6, 6).setZero();
  return Status::ok();
}

Status EkfSlam::transformWorld(const Eigen::Isometry3d& C_new_old) {
  if (!init_status_) return init_status_;
  if (Status s = checkRigid(C_new_old, "transformWorld: C_new_old"); !s) return s;
  const Eigen::Matrix3d Rc = orthonormalised(C_new_old.linear());
  const Eigen::Vector3d tc = C_new_old.translation();
  T_world_cam_.linear() = orthonormalised(Rc * T_world_cam_.linear());
  T_world_cam_.translation() = Rc * T_world_cam_.translation() + tc;
  const int n_lm = numLandmarks();
  for (int i = 0; i < n_lm; ++i) m_world_.col(i) = Rc * m_world_.col(i) + tc;
  // The stored lower triangle, by 3x3 blocks (the pose is blocks 0 and 1).
  const int blocks = stateDim() / 3;
  for (int bi = 0; bi < blocks; ++bi) {
    for (int bj = 0; bj < bi; ++bj) {
      auto B = P_.block<3, 3>(3 * bi, 3 * bj);
      B = (Rc * B * Rc.transpose()).eval();
    }
    auto D = P_.block<3, 3>(3 * bi, 3 * bi);
    const Eigen::Matrix3d full = D.selfadjointView<Lower>();
    D.triangularView<Lower>() = Rc * full * Rc.transpose();
  }
  return Status::ok();
}

Status EkfSlam::updatePosition(const Eigen::Vector3d& t_meas, const Eigen::Matrix3d& R_meas,
                               double* d2) {
  if (!init_status_) return init_status_;
  if (!t_meas.allFinite()) return Status::invalidArgument("updatePosition: t_meas is not finite");
  if (Status s = checkCovariance<3>(R_meas, true, "updatePosition: R_meas"); !s) return s;
  const int n = stateDim();
  gatherColumns(3, 3, P_lm_);  // M = P[:, t], n x 3
  const auto M = P_lm_.topRows(n);
  Eigen::Matrix3d S = M.middleRows<3>(3) + R_meas;
  S = 0.5 * (S + S.transpose()).eval();
  const Eigen::LLT<Eigen::Matrix3d> llt(S);
  if (llt.info() != Eigen::Success)
    return Status(StatusCode::kInternal,
                  "updatePosition: innovation covariance not positive definite");
  const Eigen::Vector3d z = t_meas - T_world_cam_.translation();
  // K^T = S^-1 M^T (3 x n, allocated: one call per loop correction), then P <- P - M K^T on
  // the lower triangle, column by column.
  const Eigen::MatrixXd Kt = llt.solve(M.transpose());
  if (!Kt.allFinite()) return Status(StatusCode::kInternal, "updatePosition: non-finite gain");
  dx_.head(n).noalias() = Kt.transpose() * z;
  for (int j = 0; j < n; ++j)
    P_.block(j, j, n - j, 1).noalias() -= M.bottomRows(n - j) * Kt.col(j);
  inject(n);
  if (d2) *d2 = z.dot(llt.solve(z));
  return Status::ok();
}

int EkfSlam::slotOf(int id) const { return slot_of_id_.find(id); }

void EkfSlam::gatherColumns(int c0, int k, Eigen::MatrixXd& out) const {
  const int n = stateDim();
  out.topRows(c0) = P_.block(c0, 0, k, c0).transpose();
  out.block(c0, 0, k, k) = P_.block(c0, c0, k, k).selfadjointView<Lower>();
  out.middleRows(c0 + k, n - c0 - k) = P_.block(c0 + k, c0, n - c0 - k, k);
}

Matrix6d EkfSlam::poseCovariance() const {
  return P_.topLeftCorner<6, 6>().selfadjointView<Lower>();
}

Eigen::MatrixXd EkfSlam::covariance() const {
  const int n = stateDim();
  return P_.topLeftCorner(n, n).selfadjointView<Lower>();
}

Status EkfSlam::landmark(int id, Eigen::Vector3d& m_world, Eigen::Matrix3d& cov) const {
  const int s = slotOf(id);
  if (s < 0) return Status::notFound("landmark " + std::to_string(id) + " is not in the state");
  const int o = 6 + 3 * s;
  m_world = m_world_.col(s);
  cov = P_.block<3, 3>(o, o).selfadjointView<Lower>();
  return Status::ok();
}

Status EkfSlam::predict(const Eigen::Isometry3d& T_cur_prev, const Matrix6d& R_u) {
  if (!init_status_) return init_status_;
  if (Status s = checkRigid(T_cur_prev, "predict: T_cur_prev"); !s) return s;
  if (Status s = checkCovariance<6>(R_u, false, "predict: R_u"); !s) return s;
  Matrix6d F_x, F_u;
  predictionJacobians(T_world_cam_, T_cur_prev, F_x, F_u);
  const int n = stateDim();
  const Matrix6d P_pp = poseCovariance();
  P_.topLeftCorner<6, 6>() = F_x * P_pp * F_x.transpose() + F_u * R_u * F_u.transpose();
  // Stored lower part of the cross block: P_mp = P_pm^T <- P_mp F_x^T.
  auto P_mp = P_.block(6, 0, n - 6, 6);
  P_pose_.topRows(n - 6).noalias() = P_mp * F_x.transpose();
  P_mp = P_pose_.topRows(n - 6);
  const Eigen::Isometry3d T = predictPose(T_world_cam_, T_cur_prev);
  T_world_cam_.linear() = orthonormalised(T.linear());
  T_world_cam_.translation() = T.translation();
  return Status::ok();
}

Status EkfSlam::checkObservations(const std::vector<LandmarkObservation>& obs) const {
  // Messages are built only on failure (this runs every frame).
  const auto what = [](std::size_t k) { return "update: observation " + std::to_string(k); };
  for (std::size_t k = 0; k < obs.size(); ++k) {
    if (slotOf(obs[k].id) < 0)
      return Status::invalidArgument(what(k) + ": unknown landmark id " +
                                     std::to_string(obs[k].id));
    if (!obs[k].z_cam.allFinite())
      return Status::invalidArgument(what(k) + ": z_cam is not finite");
    if (covarianceFault<3>(obs[k].R, true) != CovarianceFault::kNone)
      return checkCovariance<3>(obs[k].R, true, what(k) + ": R");
  }
  return Status::ok();
}

Status EkfSlam::update(const std::vector<LandmarkObservation>& obs,
                       std::vector<ObservationResult>& results, Executor* executor) {
  if (!init_status_) return init_status_;
  if (Status s = checkObservations(obs); !s) return s;
  results.resize(obs.size());
  // Gating of every observation against the state before any update:
  // S_i = H_p P_pp H_p^T + H_p P_pm H_m^T + H_m P_mp H_p^T + H_m P_mm H_m^T + R_i.
  const Matrix6d P_pp = poseCovariance();
  for (std::size_t k = 0; k < obs.size(); ++k) {
    const int s = slotOf(obs[k].id), o = 6 + 3 * s;
    Matrix36d H_p;
    Eigen::Matrix3d H_m;
    observationJacobians(T_world_cam_, m_world_.col(s), H_p, H_m);
    const Eigen::Matrix<double, 3, 6> P_mp = P_.block<3, 6>(o, 0);
    const Eigen::Matrix3d P_mm = P_.block<3, 3>(o, o).selfadjointView<Lower>();
    const Eigen::Matrix3d HPH_cross = H_m * P_mp * H_p.transpose();
    Eigen::Matrix3d S = H_p * P_pp * H_p.transpose() + HPH_cross + HPH_cross.transpose() +
                        H_m * P_mm * H_m.transpose() + obs[k].R;
    S = 0.5 * (S + S.transpose()).eval();
    const Eigen::Vector3d nu = obs[k].z_cam - observeLandmark(T_world_cam_, m_world_.col(s));
    const Eigen::LLT<Eigen::Matrix3d> llt(S);
    double d2 = std::numeric_limits<double>::infinity();
    if (llt.info() == Eigen::Success) d2 = nu.dot(llt.solve(nu));
    results[k] = {obs[k].id, d2 <= params_.gate_chi2, d2};
  }
  // Accepted observations, stacked in batches.
  return applyAcceptedInBatches(
      results, [&](const int* idx, int count) { return applyBatch(obs, idx, count, executor); });
}

Status EkfSlam::applyBatch(const std::vector<LandmarkObservation>& obs, const int* idx, int count,
                           Executor* executor) {
  const int n = stateDim(), m = 3 * count;
  auto M = B_.block(0, 0, n, m);
  auto nu = nu_.head(m);
  gatherColumns(0, 6, P_pose_);
  const auto P_pose = P_pose_.topRows(n);
  Matrix36d H_p;
  Eigen::Matrix3d H_m;
  // M = P H^T, one 3-column block per observation: P[:, pose] H_p^T + P[:, m_i] H_m^T.
  for (int j = 0; j < count; ++j) {
    const LandmarkObservation& o = obs[static_cast<std::size_t>(idx[j])];
    const int s = slotOf(o.id);
    observationJacobians(T_world_cam_, m_world_.col(s), H_p, H_m);
    gatherColumns(6 + 3 * s, 3, P_lm_);
    M.middleCols(3 * j, 3).noalias() = P_pose * H_p.transpose();
    M.middleCols(3 * j, 3).noalias() += P_lm_.topRows(n) * H_m.transpose();
    nu.segment<3>(3 * j) = o.z_cam - observeLandmark(T_world_cam_, m_world_.col(s));
  }
  // S = H M + R (block row i: H_p M[pose rows] + H_m M[rows of m_i]), then symmetrised.
  auto S = S_.topLeftCorner(m, m);
  for (int i = 0; i < count; ++i) {
    const LandmarkObservation& o = obs[static_cast<std::size_t>(idx[i])];
    const int s = slotOf(o.id);
    observationJacobians(T_world_cam_, m_world_.col(s), H_p, H_m);
    S.middleRows(3 * i, 3).noalias() = H_p * M.topRows(6);
    S.middleRows(3 * i, 3).noalias() += H_m * M.middleRows(6 + 3 * s, 3);
    S.block<3, 3>(3 * i, 3 * i) += o.R;
  }
  return applyStacked(m, executor);
}

Status EkfSlam::applyStacked(int m, Executor* executor) {
  const int n = stateDim();
  auto M = B_.block(0, 0, n, m);
  auto nu = nu_.head(m);
  auto S = S_.topLeftCorner(m, m);
  symmetrise(S);
  auto L = L_.topLeftCorner(m, m);
  L = S;
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(L);
  if (llt.info() != Eigen::Success)
    return Status(StatusCode::kInternal, "update: innovation covariance not positive definite");
  // T = S^-1 (Joseph: explicit, exactly symmetric) or L^-1 (optimal gain); G = M T^T, i.e.
  // G(i, j) = sum_k M(i, k) T(j, k): the gain K = M S^-1, or B = M L^-T.
  auto T = T_.topLeftCorner(m, m);
  T.setIdentity();
  if (params_.joseph_form) {
    llt.solveInPlace(T);
    symmetrise(T);
  } else {
    llt.matrixL().solveInPlace(T);
    llt.matrixL().solveInPlace(nu);  // L^-1 nu, so B L^-1 nu = M S^-1 nu = K nu
  }
  auto G = A_.block(0, 0, n, m);
  G.setZero();
  subtractProduct(G, M, T, false, executor);  // -M T^T
  G = -G;
  auto dx = dx_.head(n);
  dx.noalias() = G * nu;  // K nu
  if (!dx.allFinite() || !G.allFinite())
    return Status(StatusCode::kInternal, "update: non-finite gain");
  auto P = P_.topLeftCorner(n, n);
  if (params_.joseph_form) {
    // Lower triangle of P - [K D][M K]^T, D = M - K S (S symmetric: B(j, k) = S(k, j)).
    B_.block(0, m, n, m) = G;
    auto D = A_.block(0, m, n, m);
    D = M;
    subtractProduct(D, G, S, false, executor);
    subtractProduct(P, A_.topLeftCorner(n, 2 * m), B_.topLeftCorner(n, 2 * m), true, executor);
  } else {
    subtractProduct(P, G, G, true, executor);  // P - B B^T
  }
  inject(n);
  return Status::ok();
}

void EkfSlam::subtractProduct(Eigen::Ref<Eigen::MatrixXd> C,
                              const Eigen::Ref<const Eigen::MatrixXd>& U,
                              const Eigen::Ref<const Eigen::MatrixXd>& V, bool lower_only,
                              Executor* executor) {
  const int rows = static_cast<int>(C.rows()), cols = static_cast<int>(C.cols()),
            r = static_cast<int>(U.cols());
  if (!rank_update_) {
    if (lower_only)
      C.triangularView<Lower>() -= U * V.transpose();
    else
      C.noalias() -= U * V.transpose();
    return;
  }
  // Row pieces of (nearly) equal work: [b_k, b_{k+1}) with b_k = rows sqrt(k / p) for the
  // triangle (its first b rows hold b^2 / 2 elements), rows k / p for a full product.
  int pieces = 1;
  if (executor && rows >= 128)
    pieces = std::max(1, std::min(executor->concurrency(), params_.max_update_tasks));
  const auto bound = [&](int k) {
    if (k >= pieces) return rows;
    const double f = static_cast<double>(k) / pieces;
    return static_cast<int>(rows * (lower_only ? std::sqrt(f) : f));
  };
  const auto piece = [&](int k) {
    const int r0 = bound(k), r1 = bound(k + 1);
    if (r1 <= r0) return;
    rank_update_->rankUpdate(&C(r0, 0), C.outerStride(), U.data() + r0, U.outerStride(), V.data(),
                             V.outerStride(), r1 - r0, lower_only ? std::min(cols, r1) : cols, r,
                             lower_only, r0,
                             rank_update_ws_.data() + ws_piece_ * static_cast<std::size_t>(k));
  };
  if (pieces == 1)
    piece(0);
  else
    executor->parallelFor(pieces, piece);
}

void EkfSlam::inject(int n) {
  const auto dx = dx_.head(n);
  T_world_cam_.linear() = orthonormalised(expSO3(dx.head<3>()) * T_world_cam_.linear());
  T_world_cam_.translation() += dx.segment<3>(3);
  for (int s = 0; s < numLandmarks(); ++s) m_world_.col(s) += dx.segment<3>(6 + 3 * s);
}

Result<int> EkfSlam::addLandmark(const Eigen::Vector3d& z_cam, const Eigen::Matrix3d& R_z) {
  if (!init_status_) return init_status_;
  if (!z_cam.allFinite()) return Status::invalidArgument("addLandmark: z_cam is not finite");
  if (Status s = checkCovariance<3>(R_z, false, "addLandmark: R_z"); !s) return s;
  if (Status s = checkRoom("addLandmark"); !s) return s;
  Matrix36d G_x;
  Eigen::Matrix3d G_z;
  initJacobians(T_world_cam_, z_cam, G_x, G_z);
  const int n = stateDim(), s = numLandmarks(), o = n;
  gatherColumns(0, 6, P_pose_);
  // P_m,x = G_x P[pose, :] (rows of the new landmark, all previous columns).
  P_.block(o, 0, 3, n).noalias() = G_x * P_pose_.topRows(n).transpose();
  const Matrix6d P_pp = P_pose_.topRows<6>();
  P_.block<3, 3>(o, o) = G_x * P_pp * G_x.transpose() + G_z * R_z * G_z.transpose();
  m_world_.col(s) = initLandmark(T_world_cam_, z_cam);
  const int id = next_id_++;
  ids_.push_back(id);
  slot_of_id_.set(id, s);
  return id;
}

Result<int> EkfSlam::addLandmarkFromExactPose(const Eigen::Isometry3d& T_world_cam_exact,
                                              const Eigen::Vector3d& z_cam,
                                              const Eigen::Matrix3d& R_z) {
  if (!init_status_) return init_status_;
  if (!z_cam.allFinite() || !T_world_cam_exact.matrix().allFinite())
    return Status::invalidArgument("addLandmarkFromExactPose: z_cam or the pose is not finite");
  if (Status s = checkCovariance<3>(R_z, false, "addLandmarkFromExactPose: R_z"); !s) return s;
  if (Status s = checkRoom("addLandmarkFromExactPose"); !s) return s;
  const Eigen::Matrix3d R = T_world_cam_exact.linear();
  const int id = next_id_++;
  appendUncorrelated(id, initLandmark(T_world_cam_exact, z_cam), R * R_z * R.transpose());
  return id;
}

Status EkfSlam::restoreLandmark(int id, const Eigen::Vector3d& m_world,
                                const Eigen::Matrix3d& cov) {
  if (!init_status_) return init_status_;
  if (id < 0 || id >= next_id_)
    return Status::notFound("restoreLandmark: landmark " + std::to_string(id) + " was never added");
  if (slotOf(id) >= 0)
    return Status::failedPrecondition("restoreLandmark: landmark " + std::to_string(id) +
                                      " is in the state");
  if (!m_world.allFinite())
    return Status::invalidArgument("restoreLandmark: m_world is not finite");
  if (Status s = checkCovariance<3>(cov, false, "restoreLandmark: cov"); !s) return s;
  if (Status s = checkRoom("restoreLandmark"); !s) return s;
  appendUncorrelated(id, m_world, cov);
  return Status::ok();
}

Status EkfSlam::checkRoom(const char* what) const {
  if (numLandmarks() < params_.max_landmarks) return Status::ok();
  return Status::failedPrecondition(std::string(what) + ": the state holds max_landmarks = " +
                                    std::to_string(params_.max_landmarks) + " landmarks");
}

void EkfSlam::appendUncorrelated(int id, const Eigen::Vector3d& m_world,
                                 const Eigen::Matrix3d& cov) {
  const int n = stateDim(), s = numLandmarks();
  P_.block(n, 0, 3, n).setZero();
  P_.block<3, 3>(n, n) = cov;
  m_world_.col(s) = m_world;
  ids_.push_back(id);
  slot_of_id_.set(id, s);
}

Status EkfSlam::removeLandmark(int id, Eigen::Vector3d* m_world, Eigen::Matrix3d* cov) {
  if (!init_status_) return init_status_;
  const int s = slotOf(id);
  if (s < 0)
    return Status::notFound("removeLandmark: landmark " + std::to_string(id) +
                            " is not in the state");
  const int o = 6 + 3 * s, last = numLandmarks() - 1, ol = 6 + 3 * last;
  if (m_world) *m_world = m_world_.col(s);
  if (cov) *cov = P_.block<3, 3>(o, o).selfadjointView<Lower>();
  if (s != last) {
    // The last landmark moves to slot s: P(r, o..o+2) <- P(r, ol..ol+2) for every other r.
    // Sources lie in rows ol.., targets in rows < ol, so nothing is overwritten before use.
    P_.block(o, 0, 3, o) = P_.block(ol, 0, 3, o);
    P_.block(o + 3, o, ol - o - 3, 3) = P_.block(ol, o + 3, 3, ol - o - 3).transpose();
    P_.block<3, 3>(o, o) = P_.block<3, 3>(ol, ol);
    m_world_.col(s) = m_world_.col(last);
    ids_[static_cast<std::size_t>(s)] = ids_[static_cast<std::size_t>(last)];
    slot_of_id_.set(ids_[static_cast<std::size_t>(s)], s);
  }
  ids_.pop_back();
  slot_of_id_.erase(id);
  return Status::ok();
}

}  // namespace svslam

// EkfSlam::updateBearings: bearing (monocular) observations of the landmarks of the state
// (seed 000 part 2). The model and its Jacobian are in ekf_slam.hpp (BearingObservation); the
// gain and covariance update are update()'s (applyStacked), with 2-row blocks.
#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <string>

#include "slam/ekf_checks.hpp"
#include "slam/ekf_slam.hpp"

namespace svslam {

using Eigen::Lower;
using Matrix26d = Eigen::Matrix<double, 2, 6>;
using Matrix23d = Eigen::Matrix<double, 2, 3>;

bool EkfSlam::bearingModel(int s, Eigen::Vector2d& xy, Matrix26d& H_p, Matrix23d& H_m) const {
  const Eigen::Vector3d p = observeLandmark(T_world_cam_, m_world_.col(s));
  if (!(p.z() >= params_.bearing_min_depth_m)) return false;
  Matrix36d H_p3;
  Eigen::Matrix3d H_m3;
  observationJacobians(T_world_cam_, m_world_.col(s), H_p3, H_m3);
  const double iz = 1.0 / p.z();
  xy = Eigen::Vector2d(p.x() * iz, p.y() * iz);
  Matrix23d J;
  J << iz, 0, -xy.x() * iz, 0, iz, -xy.y() * iz;
  H_p = J * H_p3;
  H_m = J * H_m3;
  return true;
}

Status EkfSlam::updateBearings(const std::vector<BearingObservation>& obs,
                               std::vector<ObservationResult>& results, Executor* executor) {
  if (!init_status_) return init_status_;
  for (std::size_t k = 0; k < obs.size(); ++k) {
    const auto what = [&] { return "updateBearings: observation " + std::to_string(k); };
    if (slotOf(obs[k].id) < 0)
      return Status::invalidArgument(what() + ": unknown landmark id " + std::to_string(obs[k].id));
    if (!obs[k].xy.allFinite()) return Status::invalidArgument(what() + ": xy is not finite");
    const Eigen::Matrix2d& R = obs[k].R;
    if (!R.allFinite() || std::abs(R(0, 1) - R(1, 0)) > 1e-12 * (R.norm() + 1e-300) ||
        !(R(0, 0) > 0) || !(R.determinant() > 0))
      return Status::invalidArgument(what() + ": R is not symmetric positive definite");
  }
  results.resize(obs.size());
  const Matrix6d P_pp = poseCovariance();
  for (std::size_t k = 0; k < obs.size(); ++k) {
    const int s = slotOf(obs[k].id), o = 6 + 3 * s;
    Eigen::Vector2d xy;
    Matrix26d H_p;
    Matrix23d H_m;
    double d2 = std::numeric_limits<double>::infinity();
    if (bearingModel(s, xy, H_p, H_m)) {
      const Eigen::Matrix<double, 3, 6> P_mp = P_.block<3, 6>(o, 0);
      const Eigen::Matrix3d P_mm = P_.block<3, 3>(o, o).selfadjointView<Lower>();
      const Eigen::Matrix2d cross = H_m * P_mp * H_p.transpose();
      Eigen::Matrix2d S = H_p * P_pp * H_p.transpose() + cross + cross.transpose() +
                          H_m * P_mm * H_m.transpose() + obs[k].R;
      S = 0.5 * (S + S.transpose()).eval();
      const Eigen::Vector2d nu = obs[k].xy - xy;
      const Eigen::LLT<Eigen::Matrix2d> llt(S);
      if (llt.info() == Eigen::Success) d2 = nu.dot(llt.solve(nu));
    }
    results[k] = {obs[k].id, d2 <= params_.bearing_gate_chi2, d2};
  }
  return applyAcceptedInBatches(results, [&](const int* idx, int count) {
    return applyBearingBatch(obs, idx, count, executor);
  });
}

Status EkfSlam::applyBearingBatch(const std::vector<BearingObservation>& obs, const int* idx,
                                  int count, Executor* executor) {
  const int n = stateDim();
  auto M = B_.block(0, 0, n, 2 * count);
  auto nu = nu_.head(2 * count);
  gatherColumns(0, 6, P_pose_);
  const auto P_pose = P_pose_.topRows(n);
  Eigen::Vector2d xy;
  Matrix26d H_p;
  Matrix23d H_m;
  // M = P H^T, 2 columns per bearing. A bearing accepted by the gate was predicted in front of
  // the camera against this very state (an earlier batch may have moved it: the model is then
  // re-evaluated and a bearing now behind the camera is dropped from the batch).
  int used = 0;
  for (int j = 0; j < count; ++j) {
    const BearingObservation& o = obs[static_cast<std::size_t>(idx[j])];
    const int s = slotOf(o.id);
    if (!bearingModel(s, xy, H_p, H_m)) continue;
    gatherColumns(6 + 3 * s, 3, P_lm_);
    M.middleCols(2 * used, 2).noalias() = P_pose * H_p.transpose();
    M.middleCols(2 * used, 2).noalias() += P_lm_.topRows(n) * H_m.transpose();
    nu.segment<2>(2 * used) = o.xy - xy;
    ++used;
  }
  if (used == 0) return Status::ok();
  const int mu = 2 * used;
  auto S = S_.topLeftCorner(mu, mu);
  int i = 0;
  for (int j = 0; j < count; ++j) {
    const BearingObservation& o = obs[static_cast<std::size_t>(idx[j])];
    const int s = slotOf(o.id);
    if (!bearingModel(s, xy, H_p, H_m)) continue;
    S.middleRows(2 * i, 2).noalias() = H_p * M.topLeftCorner(6, mu);
    S.middleRows(2 * i, 2).noalias() += H_m * M.block(6 + 3 * s, 0, 3, mu);
    S.block<2, 2>(2 * i, 2 * i) += o.R;
    ++i;
  }
  return applyStacked(mu, executor);
}

}  // namespace svslam

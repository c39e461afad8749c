#include "eval/trajectory_metrics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>

namespace svslam {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

bool finitePose(const Eigen::Isometry3d& T) { return T.matrix().allFinite(); }

}  // namespace

Status TrajectoryEvalParams::validate() const {
  if (segment_lengths_m.empty()) return Status::invalidArgument("no segment length given");
  for (double l : segment_lengths_m)
    if (!std::isfinite(l) || l <= 0)
      return Status::invalidArgument("segment lengths must be finite and > 0");
  if (step_frames < 1) return Status::invalidArgument("step_frames must be >= 1");
  return Status::ok();
}

double rotationAngle(const Eigen::Matrix3d& R) {
  // atan2 of the skew and symmetric parts: accurate near 0 and pi, unlike acos((tr - 1) / 2).
  const Eigen::Vector3d w(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  return std::atan2(0.5 * w.norm(), 0.5 * (R.trace() - 1.0));
}

namespace {

Eigen::Isometry3d umeyama(const std::vector<Eigen::Vector3d>& est,
                          const std::vector<Eigen::Vector3d>& gt, bool with_scale,
                          double& scale) {
  const std::size_t n = est.size();
  Eigen::Vector3d mu_e = Eigen::Vector3d::Zero(), mu_g = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mu_e += est[i];
    mu_g += gt[i];
  }
  mu_e /= static_cast<double>(n);
  mu_g /= static_cast<double>(n);
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();  // cross-covariance gt x est
  double var_e = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sigma += (gt[i] - mu_g) * (est[i] - mu_e).transpose();
    var_e += (est[i] - mu_e).squaredNorm();
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) S(2, 2) = -1;  // no reflection
  scale = 1.0;
  if (with_scale && var_e > 0) scale = (svd.singularValues().asDiagonal() * S).trace() / var_e;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixU() * S * svd.matrixV().transpose();
  T.translation() = mu_g - scale * T.linear() * mu_e;
  return T;
}

}  // namespace

Eigen::Isometry3d umeyamaSe3(const std::vector<Eigen::Vector3d>& est,
                             const std::vector<Eigen::Vector3d>& gt) {
  double scale = 1;
  return umeyama(est, gt, false, scale);
}

Eigen::Isometry3d umeyamaSim3(const std::vector<Eigen::Vector3d>& est,
                              const std::vector<Eigen::Vector3d>& gt, double& scale) {
  return umeyama(est, gt, true, scale);
}

Result<TrajectoryMetrics> evaluateTrajectory(const std::vector<Eigen::Isometry3d>& gt,
                                             const std::vector<Eigen::Isometry3d>& est,
                                             const TrajectoryEvalParams& params) {
  if (Status s = params.validate(); !s) return s;
  if (gt.size() != est.size())
    return Status::invalidArgument("ground truth has " + std::to_string(gt.size()) +
                                   " poses but the estimate has " + std::to_string(est.size()));
  if (gt.size() < 3) return Status::invalidArgument("need at least 3 associated poses");
  for (std::size_t i = 0; i < gt.size(); ++i)
    if (!finitePose(gt[i]) || !finitePose(est[i]))
      return Status::invalidArgument("pose " + std::to_string(i) + " contains NaN or infinity");
  const std::size_t n = gt.size();
  TrajectoryMetrics m;
  m.frames = static_cast<int>(n);

  // KITTI devkit: path distances of the ground truth, segments from every step-th frame.
  std::vector<double> dist(n, 0.0);
  for (std::size_t i = 1; i < n; ++i)
    dist[i] = dist[i - 1] + (gt[i].translation() - gt[i - 1].translation()).norm();
  m.path_length_m = dist.back();
  double sum_t = 0, sum_r = 0;
  int total = 0;
  for (double len : params.segment_lengths_m) {
    SegmentDrift sd;
    sd.length_m = len;
    for (std::size_t first = 0; first < n; first += static_cast<std::size_t>(params.step_frames)) {
      std::size_t last = first;
      while (last < n && dist[last] <= dist[first] + len) ++last;
      if (last >= n) continue;
      const Eigen::Isometry3d delta_gt = gt[first].inverse() * gt[last];
      const Eigen::Isometry3d delta_est = est[first].inverse() * est[last];
      const Eigen::Isometry3d err = delta_est.inverse() * delta_gt;
      const double t_err = err.translation().norm() / len;
      const double r_err = rotationAngle(err.linear()) / len;
      sd.t_err_pct += 100.0 * t_err;
      sd.r_err_deg_per_m += kRadToDeg * r_err;
      sum_t += 100.0 * t_err;
      sum_r += kRadToDeg * r_err;
      ++sd.count;
      ++total;
    }
    if (sd.count > 0) {
      sd.t_err_pct /= sd.count;
      sd.r_err_deg_per_m /= sd.count;
    }
    m.segments.push_back(sd);
  }
  m.t_err_pct = total > 0 ? sum_t / total : NAN;
  m.r_err_deg_per_m = total > 0 ? sum_r / total : NAN;

  // Relative pose error between consecutive frames.
  double rpe_t = 0, rpe_r = 0;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const Eigen::Isometry3d err =
        (est[i].inverse() * est[i + 1]).inverse() * (gt[i].inverse() * gt[i + 1]);
    rpe_t += err.translation().squaredNorm();
    const double a = rotationAngle(err.linear()) * kRadToDeg;
    rpe_r += a * a;
  }
  m.rpe_trans_rmse_m = std::sqrt(rpe_t / static_cast<double>(n - 1));
  m.rpe_rot_rmse_deg = std::sqrt(rpe_r / static_cast<double>(n - 1));

  // Absolute errors, after alignment.
  std::vector<Eigen::Isometry3d> est_aligned(n), gt_ref(n);
  if (params.align != TrajectoryAlignment::kNone) {
    std::vector<Eigen::Vector3d> pe(n), pg(n);
    for (std::size_t i = 0; i < n; ++i) {
      pe[i] = est[i].translation();
      pg[i] = gt[i].translation();
    }
    const bool sim3 = params.align == TrajectoryAlignment::kSim3;
    const Eigen::Isometry3d T = sim3 ? umeyamaSim3(pe, pg, m.align_scale) : umeyamaSe3(pe, pg);
    for (std::size_t i = 0; i < n; ++i) {
      est_aligned[i] = T * est[i];
      // The scale applies to positions: s R p + t.
      est_aligned[i].translation() = m.align_scale * (T.linear() * pe[i]) + T.translation();
      gt_ref[i] = gt[i];
    }
  } else {
    const Eigen::Isometry3d g0 = gt[0].inverse(), e0 = est[0].inverse();
    for (std::size_t i = 0; i < n; ++i) {
      est_aligned[i] = e0 * est[i];
      gt_ref[i] = g0 * gt[i];
    }
  }
  double ate = 0;
  for (std::size_t i = 0; i < n; ++i)
    ate += (est_aligned[i].translation() - gt_ref[i].translation()).squaredNorm();
  m.ate_rmse_m = std::sqrt(ate / static_cast<double>(n));
  m.final_pos_err_m = (est_aligned[n - 1].translation() - gt_ref[n - 1].translation()).norm();
  // Rotation about the start (see the header): Kabsch without centring.
  {
    const Eigen::Isometry3d g0 = gt[0].inverse(), e0 = est[0].inverse();
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    std::vector<Eigen::Vector3d> pg(n), pe(n);
    for (std::size_t i = 0; i < n; ++i) {
      pg[i] = (g0 * gt[i]).translation();
      pe[i] = (e0 * est[i]).translation();
      H += pg[i] * pe[i].transpose();
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
    if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) S(2, 2) = -1;
    const Eigen::Matrix3d Q = svd.matrixU() * S * svd.matrixV().transpose();
    const Eigen::AngleAxisd aa(Q);
    m.start_rotation_deg = kRadToDeg * aa.angle();
    if (aa.angle() > 0) m.start_rotation_axis = aa.axis();
    double sum = 0;
    for (std::size_t i = 0; i < n; ++i) sum += (pg[i] - Q * pe[i]).squaredNorm();
    m.ate_after_start_rotation_m = std::sqrt(sum / static_cast<double>(n));
    m.final_pos_err_after_start_rotation_m = (pg[n - 1] - Q * pe[n - 1]).norm();
  }
  // Attitude from the poses relative to the first one, whatever the alignment: a position-only
  // alignment leaves the roll about a straight path unobservable.
  const Eigen::Matrix3d R_est = est[0].linear().transpose() * est[n - 1].linear();
  const Eigen::Matrix3d R_gt = gt[0].linear().transpose() * gt[n - 1].linear();
  m.final_att_err_deg = kRadToDeg * rotationAngle(R_est.transpose() * R_gt);
  return m;
}

Result<NeesResult> evaluateNees(const std::vector<Eigen::Isometry3d>& gt,
                                const std::vector<Eigen::Isometry3d>& est,
                                const std::vector<Eigen::Matrix<double, 6, 6>>& cov) {
  if (gt.size() != est.size() || est.size() != cov.size())
    return Status::invalidArgument("NEES: ground truth, estimate and covariances differ in count");
  if (gt.empty()) return Status::invalidArgument("NEES: empty trajectories");
  NeesResult r;
  const Eigen::Isometry3d g0 = gt[0].inverse(), e0 = est[0].inverse();
  double sum = 0, sum_pos = 0;
  int in2 = 0, in2_pos = 0;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const Eigen::Matrix<double, 6, 6>& P = cov[i];
    if (!P.allFinite())
      return Status::invalidArgument("NEES: covariance " + std::to_string(i) + " is not finite");
    Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(P);
    if (llt.info() != Eigen::Success || P.diagonal().minCoeff() <= 0) continue;
    const Eigen::Isometry3d G = g0 * gt[i], E = e0 * est[i];
    Eigen::Matrix<double, 6, 1> e;
    const Eigen::AngleAxisd aa(G.linear() * E.linear().transpose());
    e.head<3>() = aa.angle() * aa.axis();
    e.tail<3>() = G.translation() - E.translation();
    const double nees = e.dot(llt.solve(e));
    const Eigen::Matrix3d Pp = P.bottomRightCorner<3, 3>();
    const double nees_pos = e.tail<3>().dot(Pp.ldlt().solve(e.tail<3>()));
    bool all = true, pos = true;
    for (int k = 0; k < 6; ++k) {
      const bool ok = std::abs(e(k)) <= 2.0 * std::sqrt(P(k, k));
      all = all && ok;
      if (k >= 3) pos = pos && ok;
    }
    in2 += all;
    in2_pos += pos;
    sum += nees;
    sum_pos += nees_pos;
    r.nees.push_back(nees);
    ++r.frames;
  }
  if (r.frames == 0) return Status::invalidArgument("NEES: no frame has a positive covariance");
  r.mean_nees = sum / r.frames;
  r.mean_nees_position = sum_pos / r.frames;
  r.within_2sigma_pct = 100.0 * in2 / r.frames;
  r.position_within_2sigma_pct = 100.0 * in2_pos / r.frames;
  return r;
}

}  // namespace svslam

#include "motion/visual_motion.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>

#include "core/so3.hpp"

namespace svslam {
namespace {

// Weighted Umeyama (no scale) on the pairs in `idx`.
Eigen::Isometry3d weightedUmeyama(const std::vector<PointPair>& pairs, const std::vector<int>& idx,
                                  const std::vector<double>& w) {
  Eigen::Vector3d mp = Eigen::Vector3d::Zero(), mc = Eigen::Vector3d::Zero();
  double sw = 0;
  for (int i : idx) {
    const double wi = w[static_cast<std::size_t>(i)];
    mp += wi * pairs[static_cast<std::size_t>(i)].p_prev;
    mc += wi * pairs[static_cast<std::size_t>(i)].p_cur;
    sw += wi;
  }
  mp /= sw;
  mc /= sw;
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  for (int i : idx)
    S += w[static_cast<std::size_t>(i)] * (pairs[static_cast<std::size_t>(i)].p_cur - mc) *
         (pairs[static_cast<std::size_t>(i)].p_prev - mp).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(S, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) D(2, 2) = -1;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixU() * D * svd.matrixV().transpose();
  T.translation() = mc - T.linear() * mp;
  return T;
}

}  // namespace

Eigen::Matrix3d expSO3(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-12) return Eigen::Matrix3d::Identity() + hatSO3(w);
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

Eigen::Vector3d logSO3(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

Status VisualMotionParams::validate() const {
  if (!(max_point_sigma_m > 0)) return Status::invalidArgument("max_point_sigma_m must be > 0");
  if (gauss_newton_iterations < 1)
    return Status::invalidArgument("gauss_newton_iterations must be >= 1");
  if (k_start < 3) return Status::invalidArgument("k_start must be >= 3");
  if (!(reject_floor >= 0)) return Status::invalidArgument("reject_floor must be >= 0");
  if (min_inliers < 3) return Status::invalidArgument("min_inliers must be >= 3");
  if (ransac_iterations < 1) return Status::invalidArgument("ransac_iterations must be >= 1");
  if (!(ransac_chi2 > 0)) return Status::invalidArgument("ransac_chi2 must be > 0");
  return Status::ok();
}

VisualMotion::VisualMotion(const VisualMotionParams& params) : params_(params) {
  init_status_ = params_.validate();
  // Per point pair; grown once past this when a frame has more pairs.
  constexpr std::size_t kPairs = 2048;
  active_.reserve(kPairs);
  weight_.reserve(kPairs);
  inliers_.reserve(kPairs);
  kept_.reserve(kPairs);
  residuals_.reserve(kPairs);
}

Status VisualMotion::process(const std::vector<PointPair>& pairs, VisualMotionResult& out) {
  if (!init_status_) return init_status_;
  const std::size_t n = pairs.size();
  out.inlier.assign(n, 0);
  weight_.assign(n, 0.0);
  active_.clear();
  const double max_var = params_.max_point_sigma_m * params_.max_point_sigma_m;
  for (std::size_t i = 0; i < n; ++i) {
    const PointPair& p = pairs[i];
    if (!p.p_prev.allFinite() || !p.p_cur.allFinite() || !p.cov_prev.allFinite() ||
        !p.cov_cur.allFinite())
      continue;  // never let a NaN into the estimate
    const double tr = p.cov_prev.trace() + p.cov_cur.trace();
    if (p.cov_prev.trace() > max_var || p.cov_cur.trace() > max_var || !(tr > 0)) continue;
    weight_[i] = 1.0 / tr;
    active_.push_back(static_cast<int>(i));
  }
  if (static_cast<int>(active_.size()) < params_.min_inliers)
    return Status::failedPrecondition("visual motion: " + std::to_string(active_.size()) +
                                      " usable points, fewer than min_inliers");

  auto mahalanobis2 = [&](int i, const Eigen::Isometry3d& T) {
    const PointPair& p = pairs[static_cast<std::size_t>(i)];
    const Eigen::Matrix3d C = p.cov_cur + T.linear() * p.cov_prev * T.linear().transpose();
    const Eigen::Vector3d r = p.p_cur - T * p.p_prev;
    return r.dot(C.ldlt().solve(r));
  };

  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (params_.ransac) {
    std::mt19937_64 rng(params_.seed);
    std::uniform_int_distribution<std::size_t> pick(0, active_.size() - 1);
    std::size_t best_count = 0;
    std::vector<int>& sample = sample_;
    std::vector<int>& inl = inliers_;
    sample.assign(3, 0);
    for (int it = 0; it < params_.ransac_iterations; ++it) {
      for (int& s : sample) s = active_[pick(rng)];
      if (sample[0] == sample[1] || sample[1] == sample[2] || sample[0] == sample[2]) continue;
      const Eigen::Isometry3d H = weightedUmeyama(pairs, sample, weight_);
      inl.clear();
      for (int i : active_)
        if (mahalanobis2(i, H) < params_.ransac_chi2) inl.push_back(i);
      if (inl.size() > best_count) {
        best_count = inl.size();
        T = H;
      }
    }
    std::vector<int>& kept = kept_;
    kept.clear();
    for (int i : active_)
      if (mahalanobis2(i, T) < params_.ransac_chi2) kept.push_back(i);
    if (static_cast<int>(kept.size()) < params_.min_inliers)
      return Status::failedPrecondition("visual motion: RANSAC found too few inliers");
    active_.swap(kept);
  } else {
    T = weightedUmeyama(pairs, active_, weight_);
  }

  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Identity();
  auto refine = [&]() {
    for (int it = 0; it < params_.gauss_newton_iterations; ++it) {
      H.setZero();
      Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
      for (int i : active_) {
        const PointPair& p = pairs[static_cast<std::size_t>(i)];
        const Eigen::Vector3d RX = T.linear() * p.p_prev;
        const Eigen::Matrix3d W =
            (p.cov_cur + T.linear() * p.cov_prev * T.linear().transpose()).inverse();
        Eigen::Matrix<double, 3, 6> J;
        J << hatSO3(RX), -Eigen::Matrix3d::Identity();
        const Eigen::Vector3d r = p.p_cur - RX - T.translation();
        H += J.transpose() * W * J;
        g += J.transpose() * W * r;
      }
      const Eigen::Matrix<double, 6, 1> du = -H.ldlt().solve(g);
      if (!du.allFinite()) return;
      T.linear() = expSO3(du.head<3>()) * T.linear();
      T.translation() += du.tail<3>();
      if (du.norm() < 1e-12) break;
    }
  };

  // Outlier loop: k = k_start .. 3.
  for (int k = params_.k_start; k >= 3; --k) {
    refine();
    double mean = 0;
    std::vector<double>& res = residuals_;
    res.resize(active_.size());
    for (std::size_t j = 0; j < active_.size(); ++j) {
      res[j] = std::sqrt(mahalanobis2(active_[j], T));
      mean += res[j];
    }
    mean /= static_cast<double>(active_.size());
    std::vector<int>& kept = kept_;
    kept.clear();
    for (std::size_t j = 0; j < active_.size(); ++j)
      if (res[j] <= std::max(k * mean, params_.reject_floor)) kept.push_back(active_[j]);
    if (static_cast<int>(kept.size()) < params_.min_inliers)
      return Status::failedPrecondition("visual motion: too few points after outlier rejection");
    active_.swap(kept);
  }
  refine();

  // Covariance (Haralick): H^-1 (sum J^T W C W J) H^-T; with W = C^-1 this is H^-1.
  Eigen::Matrix<double, 6, 6> Hs = Eigen::Matrix<double, 6, 6>::Zero(),
                              B = Eigen::Matrix<double, 6, 6>::Zero();
  double sum_m2 = 0;
  for (int i : active_) {
    const PointPair& p = pairs[static_cast<std::size_t>(i)];
    const Eigen::Vector3d RX = T.linear() * p.p_prev;
    const Eigen::Matrix3d C = p.cov_cur + T.linear() * p.cov_prev * T.linear().transpose();
    const Eigen::Matrix3d W = C.inverse();
    Eigen::Matrix<double, 3, 6> J;
    J << hatSO3(RX), -Eigen::Matrix3d::Identity();
    Hs += J.transpose() * W * J;
    B += J.transpose() * W * C * W * J;
    sum_m2 += mahalanobis2(i, T);
    out.inlier[static_cast<std::size_t>(i)] = 1;
  }
  const Eigen::Matrix<double, 6, 6> Hinv = Hs.inverse();
  out.covariance = Hinv * B * Hinv.transpose();
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose());
  out.T_cur_prev = T;
  out.used = static_cast<int>(active_.size());
  out.rms_mahalanobis = std::sqrt(sum_m2 / static_cast<double>(active_.size()));
  if (!out.T_cur_prev.matrix().allFinite() || !out.covariance.allFinite())
    return Status::failedPrecondition("visual motion: degenerate geometry (non-finite estimate)");
  return Status::ok();
}

}  // namespace svslam

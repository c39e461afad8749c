#include "motion/disparity_offset.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "core/so3.hpp"

namespace svslam {

Status DisparityOffsetParams::validate() const {
  if (!(prior_sigma_px > 0) || !std::isfinite(prior_sigma_px))
    return Status::invalidArgument("disparity_offset.prior_sigma_px must be finite and > 0");
  if (!(max_abs_px > 0) || !std::isfinite(max_abs_px))
    return Status::invalidArgument("disparity_offset.max_abs_px must be finite and > 0");
  if (!(gate_sigma > 0)) return Status::invalidArgument("disparity_offset.gate_sigma must be > 0");
  if (min_points < 3) return Status::invalidArgument("disparity_offset.min_points must be >= 3");
  if (!(min_information >= 0) || !std::isfinite(min_information))
    return Status::invalidArgument("disparity_offset.min_information must be finite and >= 0");
  return Status::ok();
}

double disparityOffsetScale(double z_m, double f_times_b, double delta_px) {
  if (!(z_m > 0) || !(f_times_b > 0)) return 1.0;
  const double den = 1.0 + delta_px * z_m / f_times_b;
  return den > 0.1 ? 1.0 / den : 1.0;
}

DisparityOffsetEstimator::DisparityOffsetEstimator(const DisparityOffsetParams& params,
                                                   double f_times_b)
    : params_(params), f_times_b_(f_times_b) {
  init_status_ = params_.validate();
  if (init_status_ && !(f_times_b > 0 && std::isfinite(f_times_b)))
    init_status_ = Status::invalidArgument("disparity offset: f * b must be finite and > 0");
  information_ = 1.0 / (params_.prior_sigma_px * params_.prior_sigma_px);
}

double DisparityOffsetEstimator::sigmaPx() const { return 1.0 / std::sqrt(information_); }

Status DisparityOffsetEstimator::process(const std::vector<PointPair>& pairs,
                                         const std::vector<std::uint8_t>& inlier,
                                         const Eigen::Isometry3d& T_cur_prev,
                                         DisparityOffsetFrame& out) {
  out = DisparityOffsetFrame{};
  if (!init_status_) return init_status_;
  if (inlier.size() != pairs.size())
    return Status::invalidArgument("disparity offset: inlier flags differ in size from the pairs");
  if (!params_.enabled) return Status::ok();
  const Eigen::Matrix3d R = T_cur_prev.linear();
  const Eigen::Vector3d t = T_cur_prev.translation();
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> h = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
  double c = 0, e = 0;
  int n = 0;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (!inlier[i]) continue;
    const PointPair& p = pairs[i];
    const Eigen::Vector3d RX = R * p.p_prev;
    const Eigen::Matrix3d W = (p.cov_cur + R * p.cov_prev * R.transpose()).inverse();
    if (!W.allFinite()) continue;
    Eigen::Matrix<double, 3, 6> J;
    J << hatSO3(RX), -Eigen::Matrix3d::Identity();
    // j at the point both frames agree on (their mean, in each frame), not at the measured
    // points: measured depths enter r too, and j r would then carry a bias of about
    // -4 z sigma_z^2 / (f b) per point (errors in variables) that pushes delta up.
    const Eigen::Vector3d X_prev = 0.5 * (p.p_prev + R.transpose() * (p.p_cur - t));
    const Eigen::Vector3d RX_mean = R * X_prev;
    const Eigen::Vector3d X_cur = RX_mean + t;
    const Eigen::Vector3d j =
        -(X_cur.z() / f_times_b_) * X_cur + (X_prev.z() / f_times_b_) * RX_mean;
    const Eigen::Vector3d r = p.p_cur - RX - t;
    const Eigen::Vector3d Wj = W * j;
    H += J.transpose() * W * J;
    h += J.transpose() * Wj;
    g += J.transpose() * W * r;
    c += j.dot(Wj);
    e += Wj.dot(r);
    ++n;
  }
  if (n < params_.min_points) return Status::ok();
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(H);
  if (ldlt.info() != Eigen::Success) return Status::ok();
  const Eigen::Matrix<double, 6, 1> Hh = ldlt.solve(h);
  const double info = c - h.dot(Hh);
  if (!(info > 0) || !std::isfinite(info)) return Status::ok();
  const double estimate = offset_px_ + (Hh.dot(g) - e) / info;
  if (!std::isfinite(estimate)) return Status::ok();
  out.estimate_px = estimate;
  out.information = info;
  const double gate = params_.gate_sigma * std::sqrt(1.0 / info + 1.0 / information_);
  if (info < params_.min_information || std::abs(estimate - offset_px_) > gate)
    return Status::ok();
  out.used = true;
  ++frames_used_;
  information_ += info;
  weighted_sum_ += info * estimate;
  offset_px_ = std::clamp(weighted_sum_ / information_, -params_.max_abs_px, params_.max_abs_px);
  return Status::ok();
}

}  // namespace svslam

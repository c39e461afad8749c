#include "slam/bearing_initializer.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace svslam {

Status BearingInitParams::validate() const {
  if (!(r_min_m > 0) || !std::isfinite(r_min_m))
    return Status::invalidArgument("bearing_init.r_min_m must be finite and > 0");
  if (!(r_max_m > r_min_m) || !std::isfinite(r_max_m))
    return Status::invalidArgument("bearing_init.r_max_m must be finite and > r_min_m");
  if (num_samples < 10 || num_samples > 1000000)
    return Status::invalidArgument("bearing_init.num_samples must be in [10, 1000000]");
  if (max_draws < num_samples)
    return Status::invalidArgument("bearing_init.max_draws must be >= num_samples");
  if (!(box_sigmas >= 2 && box_sigmas <= 20))
    return Status::invalidArgument("bearing_init.box_sigmas must be in [2, 20]");
  if (!(min_parallax_sigmas >= 0) || !std::isfinite(min_parallax_sigmas))
    return Status::invalidArgument("bearing_init.min_parallax_sigmas must be finite and >= 0");
  return Status::ok();
}

namespace {

// Angle between unit vector d and vector v (rad, [0, pi]), accurate for small angles.
double angleBetween(const Eigen::Vector2d& d, const Eigen::Vector2d& v) {
  return std::abs(std::atan2(d.x() * v.y() - d.y() * v.x(), d.dot(v)));
}
double angleBetween(const Eigen::Vector3d& d, const Eigen::Vector3d& v) {
  return std::atan2(d.cross(v).norm(), d.dot(v));
}

// Uniform in [0, 1) from the top 53 bits of one 64-bit output (platform independent).
double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);
}

}  // namespace

template <int D>
BearingInitializer<D>::BearingInitializer(const BearingInitParams& params) : params_(params) {
  init_status_ = params_.validate();
  if (init_status_) samples_.reserve(static_cast<std::size_t>(params_.num_samples));
}

template <int D>
double BearingInitializer<D>::logDensity(const std::vector<BearingView<D>>& views,
                                         const Vec& x) const {
  double lp = 0;
  for (const BearingView<D>& v : views) {
    const Vec dx = x - v.origin_m;
    const double r = dx.norm();
    if (!(r >= params_.r_min_m && r <= params_.r_max_m))
      return -std::numeric_limits<double>::infinity();
    const double a = angleBetween(v.direction, dx) / v.sigma_rad;
    lp += -(D - 1) * std::log(r) - 0.5 * a * a;
  }
  return lp;
}

template <int D>
Status BearingInitializer<D>::process(const std::vector<BearingView<D>>& views,
                                      std::uint64_t stream, BearingEstimate<D>& out) {
  using Mat = Eigen::Matrix<double, D, D>;
  if (!init_status_) return init_status_;
  out = BearingEstimate<D>{};
  if (views.size() < 2)
    return Status::invalidArgument("bearing initialisation needs at least two views, got " +
                                   std::to_string(views.size()));
  double sigma_max = 0;
  for (std::size_t k = 0; k < views.size(); ++k) {
    const BearingView<D>& v = views[k];
    const std::string what = "bearing initialisation: view " + std::to_string(k);
    if (!v.origin_m.allFinite() || !v.direction.allFinite())
      return Status::invalidArgument(what + ": origin or direction is not finite");
    if (std::abs(v.direction.norm() - 1.0) > 1e-6)
      return Status::invalidArgument(what + ": direction is not a unit vector");
    if (!(v.sigma_rad > 0) || !std::isfinite(v.sigma_rad) || v.sigma_rad > 0.5)
      return Status::invalidArgument(what + ": sigma_rad must be in (0, 0.5]");
    sigma_max = std::max(sigma_max, v.sigma_rad);
  }
  // Parallax: the largest angle between two bearings.
  for (std::size_t i = 0; i < views.size(); ++i)
    for (std::size_t j = i + 1; j < views.size(); ++j)
      out.parallax_rad =
          std::max(out.parallax_rad, angleBetween(views[i].direction, views[j].direction));
  if (out.parallax_rad < params_.min_parallax_sigmas * sigma_max || out.parallax_rad < 1e-9) {
    out.outcome = BearingEstimate<D>::Outcome::kTooParallel;
    return Status::ok();
  }
  // Intersection: argmin_x sum_k |(I - d_k d_k^T)(x - o_k)|^2.
  Mat A = Mat::Zero();
  Vec b = Vec::Zero();
  for (const BearingView<D>& v : views) {
    const Mat Q = Mat::Identity() - v.direction * v.direction.transpose();
    A += Q;
    b += Q * v.origin_m;
  }
  Vec x0 = A.fullPivLu().solve(b);
  bool in_range = x0.allFinite();
  for (const BearingView<D>& v : views) {
    const double r = (x0 - v.origin_m).norm();
    in_range = in_range && v.direction.dot(x0 - v.origin_m) > 0 && r >= params_.r_min_m &&
               r <= params_.r_max_m;
  }
  if (!in_range) {
    // Rays that do not meet in range. Cones within 3 sigma of each other still overlap along
    // their length: the intersection is then the densest point of the first bearing (200
    // ranges, geometric steps over [R_min, R_max]). Wider apart, the bearings contradict.
    if (out.parallax_rad > 3 * sigma_max) {
      out.outcome = BearingEstimate<D>::Outcome::kOutOfRange;
      return Status::ok();
    }
    double best = -std::numeric_limits<double>::infinity();
    const double ratio = std::pow(params_.r_max_m / params_.r_min_m, 1.0 / 199);
    double t = params_.r_min_m;
    for (int i = 0; i < 200; ++i, t *= ratio) {
      const Vec x = views[0].origin_m + t * views[0].direction;
      const double lp = logDensity(views, x);
      if (lp > best) {
        best = lp;
        x0 = x;
      }
    }
    if (!std::isfinite(best)) {
      out.outcome = BearingEstimate<D>::Outcome::kOutOfRange;
      return Status::ok();
    }
  }
  out.intersection_m = x0;
  // Linearised covariance, its axes and the box.
  Mat info = Mat::Zero();
  for (const BearingView<D>& v : views) {
    const double s = v.sigma_rad * (x0 - v.origin_m).norm();
    info += (Mat::Identity() - v.direction * v.direction.transpose()) / (s * s);
  }
  const Eigen::SelfAdjointEigenSolver<Mat> eig(info);
  if (eig.info() != Eigen::Success || !(eig.eigenvalues().minCoeff() > 0)) {
    out.outcome = BearingEstimate<D>::Outcome::kTooParallel;
    return Status::ok();
  }
  const Mat axes = eig.eigenvectors();
  Vec lo, hi;  // box extent along each axis, m (asymmetric once a side has grown)
  Vec sig;
  for (int k = 0; k < D; ++k) {
    sig(k) = 1.0 / std::sqrt(eig.eigenvalues()(k));
    hi(k) = std::min(params_.box_sigmas * sig(k), params_.r_max_m);
    lo(k) = -hi(k);
  }
  double log_pmax = logDensity(views, x0);
  if (!std::isfinite(log_pmax)) {
    out.outcome = BearingEstimate<D>::Outcome::kOutOfRange;
    return Status::ok();
  }
  // Rejection sampling. After a pass, a side of the box holding more than 0.1 % of the kept
  // samples within half a linearised sigma of its edge cuts a tail (the density is skewed toward
  // far ranges when the parallax is small): that side grows by half and the pass is repeated
  // (at most max_growths times); a Gaussian leaves 2e-4 per side there at box_sigmas = 4.
  std::mt19937_64 rng(params_.seed * 0x9E3779B97F4A7C15ULL ^ (stream + 0x632BE59BD9B4E019ULL));
  const std::size_t want = static_cast<std::size_t>(params_.num_samples);
  constexpr int max_growths = 8;
  int draws = 0;
  for (int growth = 0;; ++growth) {
    samples_.clear();
    while (samples_.size() < want) {
      if (draws >= params_.max_draws)
        return Status::failedPrecondition(
            "bearing initialisation: " + std::to_string(samples_.size()) + " of " +
            std::to_string(want) + " samples accepted in max_draws = " +
            std::to_string(params_.max_draws) + " draws");
      ++draws;
      Vec u;
      for (int k = 0; k < D; ++k) u(k) = lo(k) + (hi(k) - lo(k)) * uniform01(rng);
      const Vec s = x0 + axes * u;
      const double nu = uniform01(rng);
      const double lp = logDensity(views, s);
      if (lp > log_pmax) {
        // p_max was too low: raise it to p(s) and keep each sample accepted so far with
        // probability p_max_old / p_max_new (it was accepted with p / p_max_old; now p /
        // p_max_new, as for a fresh draw), s with probability 1.
        const double keep = std::exp(log_pmax - lp);
        std::size_t kept = 0;
        for (const Vec& t : samples_)
          if (uniform01(rng) < keep) samples_[kept++] = t;
        samples_.resize(kept);
        samples_.push_back(s);
        log_pmax = lp;
        ++out.restarts;
        continue;
      }
      if (nu < std::exp(lp - log_pmax)) samples_.push_back(s);
    }
    if (growth == max_growths) break;
    bool grown = false;
    for (int k = 0; k < D; ++k) {
      std::size_t near_lo = 0, near_hi = 0;
      for (const Vec& s : samples_) {
        const double c = axes.col(k).dot(s - x0);
        near_lo += c < lo(k) + 0.5 * sig(k) ? 1 : 0;
        near_hi += c > hi(k) - 0.5 * sig(k) ? 1 : 0;
      }
      const std::size_t limit = want / 1000;
      if (near_lo > limit && -lo(k) < params_.r_max_m) {
        lo(k) -= 0.5 * (hi(k) - lo(k));
        grown = true;
      }
      if (near_hi > limit && hi(k) < params_.r_max_m) {
        hi(k) += 0.5 * (hi(k) - lo(k));
        grown = true;
      }
    }
    if (!grown) break;
    ++out.growths;
  }
  Vec mean = Vec::Zero();
  for (const Vec& s : samples_) mean += s;
  mean /= static_cast<double>(samples_.size());
  Mat cov = Mat::Zero();
  for (const Vec& s : samples_) cov += (s - mean) * (s - mean).transpose();
  cov /= static_cast<double>(samples_.size() - 1);
  out.mean_m = mean;
  out.cov_m2 = 0.5 * (cov + cov.transpose());
  out.draws = draws;
  out.outcome = BearingEstimate<D>::Outcome::kInitialised;
  return Status::ok();
}

template class BearingInitializer<2>;
template class BearingInitializer<3>;

}  // namespace svslam

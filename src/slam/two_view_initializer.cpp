#include "slam/two_view_initializer.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>

#include "core/so3.hpp"
#include "slam/two_view_models.hpp"

namespace svslam {

Status TwoViewInitializerParams::validate() const {
  if (ransac_iterations < 1 || ransac_iterations > 100000)
    return Status::invalidArgument("two_view.ransac_iterations must be in [1, 100000]");
  if (!(inlier_threshold_px > 0) || !std::isfinite(inlier_threshold_px))
    return Status::invalidArgument("two_view.inlier_threshold_px must be finite and > 0");
  if (min_inliers < 8) return Status::invalidArgument("two_view.min_inliers must be >= 8");
  if (!(min_parallax_deg > 0 && min_parallax_deg <= 90))
    return Status::invalidArgument("two_view.min_parallax_deg must be in (0, 90]");
  if (!(homography_ratio >= 0 && homography_ratio <= 1))
    return Status::invalidArgument("two_view.homography_ratio must be in [0, 1]");
  if (!(min_best_ratio > 0 && min_best_ratio <= 1))
    return Status::invalidArgument("two_view.min_best_ratio must be in (0, 1]");
  return Status::ok();
}

namespace {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr int kSampleSize = 8;
constexpr double kMaxCosParallax = 0.99998;  // triangulation angle floor, 0.36 deg
constexpr int kMaxRefits = 3;
constexpr int kRefineIterations = 20;
constexpr double kRadToDeg = 180.0 / M_PI;

using two_view::fitEssential;
using two_view::fitHomography;
using two_view::hom;
using two_view::normalisePoints;
using two_view::scoreEssential;
using two_view::scoreHomography;

double angleDeg(const Vector3d& a, const Vector3d& b) {
  return kRadToDeg * std::atan2(a.cross(b).norm(), a.dot(b));
}

// Levenberg-Marquardt from p = 0 on |r(p)|^2, central-difference Jacobian (K parameters).
template <int K, class Residuals>
Eigen::Matrix<double, K, 1> levenbergMarquardt(const Residuals& residuals) {
  using VecK = Eigen::Matrix<double, K, 1>;
  using MatK = Eigen::Matrix<double, K, K>;
  VecK p = VecK::Zero();
  Eigen::VectorXd r = residuals(p);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  Eigen::MatrixXd J(r.size(), K);
  for (int it = 0; it < kRefineIterations; ++it) {
    for (int j = 0; j < K; ++j) {
      VecK h = VecK::Zero();
      h(j) = 1e-6;
      J.col(j) = (residuals(p + h) - residuals(p - h)) / 2e-6;
    }
    const MatK A = J.transpose() * J;
    const VecK g = J.transpose() * r;
    bool improved = false;
    while (!improved && lambda < 1e8) {
      MatK D = A;
      D.diagonal() += lambda * (A.diagonal().array() + 1e-12).matrix();
      const VecK dp = D.ldlt().solve(-g);
      const Eigen::VectorXd r2 = residuals(p + dp);
      const double cost2 = r2.squaredNorm();
      if (dp.allFinite() && cost2 < cost) {
        improved = true;
        p += dp;
        const bool converged = cost - cost2 < 1e-10 * cost;
        r = r2;
        cost = cost2;
        lambda = std::max(1e-9, 0.1 * lambda);
        if (converged) return p;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;
  }
  return p;
}

double median(std::vector<double>& v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

TwoViewInitializer::TwoViewInitializer(const TwoViewInitializerParams& params) : params_(params) {
  init_status_ = params_.validate();
}

int TwoViewInitializer::checkPose(const Candidate& c, const std::vector<std::uint8_t>& mask,
                                  std::vector<double>* parallax) {
  const std::vector<Vector2d>& x0 = *x0_;
  const std::vector<Vector2d>& x1 = *x1_;
  const std::size_t n = x0.size();
  good_.assign(n, 0);
  pts_.assign(n, Vector3d::Zero());
  if (parallax) parallax->clear();
  const Vector3d c1 = -c.R.transpose() * c.t;  // view 1's centre in view 0's frame
  const double th2 = 4.0 * params_.inlier_threshold_px * params_.inlier_threshold_px /
                     (f_px_ * f_px_);  // (2 sigma)^2, normalised units
  int count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!mask[i]) continue;
    // Midpoint: minimise |l0 a + t - l1 b| (view 1's frame) over the depths l0, l1.
    const Vector3d a = c.R * hom(x0[i]), b = hom(x1[i]);
    const double aa = a.dot(a), bb = b.dot(b), ab = a.dot(b), at = a.dot(c.t), bt = b.dot(c.t);
    const double det = aa * bb - ab * ab;
    if (!(det > 1e-14 * aa * bb)) continue;  // parallel rays
    const double l0 = (ab * bt - at * bb) / det, l1 = (aa * bt - ab * at) / det;
    const Vector3d p1 = 0.5 * (l0 * a + c.t + l1 * b);
    const Vector3d p0 = c.R.transpose() * (p1 - c.t);
    if (!p0.allFinite() || !(p0.z() > 0) || !(p1.z() > 0)) continue;
    const Vector3d r1 = p0 - c1;
    if (p0.dot(r1) / (p0.norm() * r1.norm()) >= kMaxCosParallax) continue;
    if ((p0.head<2>() / p0.z() - x0[i]).squaredNorm() > th2) continue;
    if ((p1.head<2>() / p1.z() - x1[i]).squaredNorm() > th2) continue;
    good_[i] = 1;
    pts_[i] = p0;
    ++count;
    if (parallax) parallax->push_back(angleDeg(p0, r1));
  }
  return count;
}

Status TwoViewInitializer::process(const std::vector<Vector2d>& x0, const std::vector<Vector2d>& x1,
                                   double f_px, std::uint64_t stream, TwoViewResult& out) {
  if (!init_status_) return init_status_;
  out = TwoViewResult{};
  if (x0.size() != x1.size())
    return Status::invalidArgument("two-view initialisation: " + std::to_string(x0.size()) +
                                   " points in view 0 but " + std::to_string(x1.size()) +
                                   " in view 1");
  if (!(f_px > 0) || !std::isfinite(f_px))
    return Status::invalidArgument("two-view initialisation: f_px must be finite and > 0");
  for (std::size_t i = 0; i < x0.size(); ++i)
    if (!x0[i].allFinite() || !x1[i].allFinite())
      return Status::invalidArgument("two-view initialisation: correspondence " +
                                     std::to_string(i) + " is not finite");
  const int n = static_cast<int>(x0.size());
  out.inlier.assign(x0.size(), 0);
  out.p0.assign(x0.size(), Vector3d::Zero());
  if (n < std::max(kSampleSize, params_.min_inliers)) {
    out.why = "too few correspondences";
    return Status::ok();
  }
  x0_ = &x0;
  x1_ = &x1;
  f_px_ = f_px;
  const Matrix3d T0 = normalisePoints(x0, n0_), T1 = normalisePoints(x1, n1_);
  const double k = f_px * f_px / (params_.inlier_threshold_px * params_.inlier_threshold_px);
  mask_e_.assign(x0.size(), 0);
  mask_h_.assign(x0.size(), 0);
  mask_tmp_.assign(x0.size(), 0);

  // 1. RANSAC, both models on the same samples, then refits to the inliers.
  std::mt19937_64 rng(params_.seed * 0x9E3779B97F4A7C15ULL ^ (stream + 0x632BE59BD9B4E019ULL));
  perm_.resize(x0.size());
  std::iota(perm_.begin(), perm_.end(), 0);
  Matrix3d E_best = Matrix3d::Zero(), H_best = Matrix3d::Zero(), M;
  double s_e = 0, s_h = 0;
  for (int it = 0; it < params_.ransac_iterations; ++it) {
    for (int j = 0; j < kSampleSize; ++j) {
      const int r = j + static_cast<int>(rng() % static_cast<std::uint64_t>(n - j));
      std::swap(perm_[j], perm_[r]);
    }
    if (fitEssential(n0_, n1_, perm_.data(), kSampleSize, T0, T1, M)) {
      const double s = scoreEssential(M, x0, x1, k, mask_tmp_);
      if (s > s_e) {
        s_e = s;
        E_best = M;
        mask_e_.swap(mask_tmp_);
      }
    }
    if (fitHomography(n0_, n1_, perm_.data(), kSampleSize, T0, T1, M)) {
      const double s = scoreHomography(M, x0, x1, k, mask_tmp_);
      if (s > s_h) {
        s_h = s;
        H_best = M;
        mask_h_.swap(mask_tmp_);
      }
    }
  }
  const auto refit = [&](bool essential, Matrix3d& best, double& score,
                         std::vector<std::uint8_t>& mask) {
    for (int r = 0; r < kMaxRefits && score > 0; ++r) {
      fit_idx_.clear();
      for (int i = 0; i < n; ++i)
        if (mask[i]) fit_idx_.push_back(i);
      if (static_cast<int>(fit_idx_.size()) < kSampleSize) return;
      const int m = static_cast<int>(fit_idx_.size());
      const bool ok = essential ? fitEssential(n0_, n1_, fit_idx_.data(), m, T0, T1, M)
                                : fitHomography(n0_, n1_, fit_idx_.data(), m, T0, T1, M);
      if (!ok) return;
      const double s = essential ? scoreEssential(M, x0, x1, k, mask_tmp_)
                                 : scoreHomography(M, x0, x1, k, mask_tmp_);
      if (!(s > score)) return;
      score = s;
      best = M;
      mask.swap(mask_tmp_);
    }
  };
  refit(true, E_best, s_e, mask_e_);
  refit(false, H_best, s_h, mask_h_);
  fit_idx_.clear();
  if (!(s_e + s_h > 0)) {
    out.why = "no model";
    return Status::ok();
  }
  out.score_ratio_h = s_h / (s_h + s_e);
  const bool use_h = out.score_ratio_h > params_.homography_ratio;
  out.model = use_h ? TwoViewResult::Model::kHomography : TwoViewResult::Model::kEssential;
  const std::vector<std::uint8_t>& mask = use_h ? mask_h_ : mask_e_;
  if (std::count(mask.begin(), mask.end(), 1) < params_.min_inliers) {
    out.why = "too few inliers";
    return Status::ok();
  }

  // 2. Pose candidates.
  std::array<Candidate, 8> cands;
  int num_cands = 0;
  if (!use_h) {
    const Eigen::JacobiSVD<Matrix3d> svd(E_best, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Matrix3d U = svd.matrixU(), V = svd.matrixV();
    if (U.determinant() < 0) U = -U;
    if (V.determinant() < 0) V = -V;
    Matrix3d W;
    W << 0, -1, 0, 1, 0, 0, 0, 0, 1;
    const Matrix3d Ra = U * W * V.transpose(), Rb = U * W.transpose() * V.transpose();
    const Vector3d t = U.col(2);
    cands[num_cands++] = {Ra, t};
    cands[num_cands++] = {Ra, -t};
    cands[num_cands++] = {Rb, t};
    cands[num_cands++] = {Rb, -t};
  } else {
    // H refined on its inliers (symmetric transfer error, px), then Faugeras' decomposition
    // (ORB-SLAM's ReconstructH); H is already in normalised units.
    H_best /= H_best.norm();
    for (int i = 0; i < n; ++i)
      if (mask[i]) fit_idx_.push_back(i);
    const Eigen::Matrix<double, 9, 1> dh =
        levenbergMarquardt<9>([&](const Eigen::Matrix<double, 9, 1>& p) {
          const Matrix3d H = H_best + Eigen::Map<const Matrix3d>(p.data());
          const Matrix3d Hinv = H.inverse();
          Eigen::VectorXd r(4 * fit_idx_.size());
          for (std::size_t j = 0; j < fit_idx_.size(); ++j) {
            const int i = fit_idx_[j];
            const Vector3d a = H * hom(x0[i]), b = Hinv * hom(x1[i]);
            r.segment<2>(4 * j) = f_px * (a.head<2>() / a.z() - x1[i]);
            r.segment<2>(4 * j + 2) = f_px * (b.head<2>() / b.z() - x0[i]);
          }
          return r;
        });
    if (dh.allFinite()) H_best += Eigen::Map<const Matrix3d>(dh.data());
    const Eigen::JacobiSVD<Matrix3d> svd(H_best, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Matrix3d& U = svd.matrixU();
    const Matrix3d& V = svd.matrixV();
    const double d1 = svd.singularValues()(0), d2 = svd.singularValues()(1),
                 d3 = svd.singularValues()(2);
    if (!(d2 > 1e-12 * d1)) {
      out.why = "no model";
      return Status::ok();
    }
    if (!(d1 - d3 > 1e-9 * d1)) {  // H ~ a rotation: no translation to recover
      out.why = "low parallax";
      return Status::ok();
    }
    const double s = U.determinant() * V.determinant();
    const double a1 = std::sqrt(std::max(0.0, (d1 * d1 - d2 * d2) / (d1 * d1 - d3 * d3)));
    const double a3 = std::sqrt(std::max(0.0, (d2 * d2 - d3 * d3) / (d1 * d1 - d3 * d3)));
    const double x1s[4] = {a1, a1, -a1, -a1}, x3s[4] = {a3, -a3, a3, -a3};
    const double root = std::sqrt(std::max(0.0, (d1 * d1 - d2 * d2) * (d2 * d2 - d3 * d3)));
    const double sth = root / ((d1 + d3) * d2), cth = (d2 * d2 + d1 * d3) / ((d1 + d3) * d2);
    const double sphi = root / ((d1 - d3) * d2), cphi = (d1 * d3 - d2 * d2) / ((d1 - d3) * d2);
    const double signs[4] = {1, -1, -1, 1};
    for (int i = 0; i < 4; ++i) {  // d' = d2
      Matrix3d Rp;
      Rp << cth, 0, -signs[i] * sth, 0, 1, 0, signs[i] * sth, 0, cth;
      cands[num_cands++] = {s * U * Rp * V.transpose(),
                            (U * Vector3d(x1s[i], 0, -x3s[i])).normalized()};
    }
    for (int i = 0; i < 4; ++i) {  // d' = -d2
      Matrix3d Rp;
      Rp << cphi, 0, signs[i] * sphi, 0, -1, 0, signs[i] * sphi, 0, -cphi;
      cands[num_cands++] = {s * U * Rp * V.transpose(),
                            (U * Vector3d(x1s[i], 0, x3s[i])).normalized()};
    }
  }
  std::array<int, 8> good{};
  int best = 0;
  for (int c = 0; c < num_cands; ++c) {
    good[c] = checkPose(cands[c], mask, nullptr);
    if (good[c] > good[best]) best = c;
  }
  int second = 0;
  for (int c = 0; c < num_cands; ++c)
    if (c != best) second = std::max(second, good[c]);

  if (good[best] < params_.min_inliers) {
    // Few good points: low parallax when, for every candidate rotation, the bearings of the
    // model's inliers are nearly parallel once rotated (e.g. a pure rotation).
    double comp = std::numeric_limits<double>::infinity();
    for (int c = 0; c < num_cands; ++c) {
      angles_.clear();
      for (int i = 0; i < n; ++i)
        if (mask[i]) angles_.push_back(angleDeg(cands[c].R * hom(x0[i]), hom(x1[i])));
      comp = std::min(comp, median(angles_));
    }
    out.median_parallax_deg = comp;
    out.why = comp < params_.min_parallax_deg ? "low parallax" : "too few inliers";
    return Status::ok();
  }
  if (!use_h) {
    // The pose refined on its good points: Sampson distance (px) to E = [t]x R, R = exp(w) R0,
    // t = unit(t0 + a b1 + b b2) with (b1, b2) a basis of the plane normal to t0.
    const Candidate c0 = cands[best];
    const Eigen::JacobiSVD<Matrix3d> tsvd(c0.t * c0.t.transpose(), Eigen::ComputeFullU);
    const Vector3d b1 = tsvd.matrixU().col(1), b2 = tsvd.matrixU().col(2);
    checkPose(c0, mask, nullptr);
    for (int i = 0; i < n; ++i)
      if (good_[i]) fit_idx_.push_back(i);
    const auto pose = [&](const Eigen::Matrix<double, 5, 1>& p) {
      const Vector3d w = p.head<3>();
      const double angle = w.norm();
      const Matrix3d dR =
          angle > 0 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() : Matrix3d::Identity();
      return Candidate{dR * c0.R, (c0.t + p(3) * b1 + p(4) * b2).normalized()};
    };
    const Eigen::Matrix<double, 5, 1> dp =
        levenbergMarquardt<5>([&](const Eigen::Matrix<double, 5, 1>& p) {
          const Candidate c = pose(p);
          const Matrix3d E = hatSO3(c.t) * c.R;
          Eigen::VectorXd r(fit_idx_.size());
          for (std::size_t j = 0; j < fit_idx_.size(); ++j) {
            const Vector3d a = hom(x0[fit_idx_[j]]), b = hom(x1[fit_idx_[j]]);
            const Vector3d l1 = E * a, l0 = E.transpose() * b;
            r(j) = f_px * b.dot(l1) /
                   std::sqrt(l1.head<2>().squaredNorm() + l0.head<2>().squaredNorm());
          }
          return r;
        });
    if (dp.allFinite()) cands[best] = pose(dp);
  }
  out.num_inliers = checkPose(cands[best], mask, &angles_);  // good_, pts_ of the best
  out.median_parallax_deg = median(angles_);
  if (out.median_parallax_deg < params_.min_parallax_deg) {
    out.why = "low parallax";
    return Status::ok();
  }
  if (second >= params_.min_best_ratio * good[best]) {
    out.why = "ambiguous";
    return Status::ok();
  }
  out.initialised = true;
  out.R_1_0 = cands[best].R;
  out.t_1_0 = cands[best].t;
  for (int i = 0; i < n; ++i) {
    out.inlier[i] = good_[i];
    if (good_[i]) out.p0[i] = pts_[i];
  }
  return Status::ok();
}

}  // namespace svslam

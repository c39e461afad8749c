#include "motion/rotation_alignment.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "motion/visual_motion.hpp"

namespace svslam {
namespace {

// Bilinear sample of img and of its central-difference gradient at (x, y); false when the 4x4
// neighbourhood the gradient needs is not inside the image.
bool sample(const Image<float>& img, double x, double y, double& v, double& gx, double& gy) {
  const int x0 = static_cast<int>(std::floor(x));
  const int y0 = static_cast<int>(std::floor(y));
  if (x0 < 1 || y0 < 1 || x0 + 2 >= img.width() || y0 + 2 >= img.height()) return false;
  const double fx = x - x0, fy = y - y0;
  auto at = [&](int xx, int yy) { return static_cast<double>(img.view()(xx, yy)); };
  auto bil = [&](double a00, double a10, double a01, double a11) {
    return (1 - fy) * ((1 - fx) * a00 + fx * a10) + fy * ((1 - fx) * a01 + fx * a11);
  };
  v = bil(at(x0, y0), at(x0 + 1, y0), at(x0, y0 + 1), at(x0 + 1, y0 + 1));
  auto dx = [&](int xx, int yy) { return 0.5 * (at(xx + 1, yy) - at(xx - 1, yy)); };
  auto dy = [&](int xx, int yy) { return 0.5 * (at(xx, yy + 1) - at(xx, yy - 1)); };
  gx = bil(dx(x0, y0), dx(x0 + 1, y0), dx(x0, y0 + 1), dx(x0 + 1, y0 + 1));
  gy = bil(dy(x0, y0), dy(x0 + 1, y0), dy(x0, y0 + 1), dy(x0 + 1, y0 + 1));
  return true;
}

PinholeCamera atLevel(const PinholeCamera& c, int level) {
  const double s = 1.0 / static_cast<double>(1 << level);
  PinholeCamera l = c;
  l.fx_px = c.fx_px * s;
  l.fy_px = c.fy_px * s;
  l.cx_px = (c.cx_px + 0.5) * s - 0.5;
  l.cy_px = (c.cy_px + 0.5) * s - 0.5;
  return l;
}

}  // namespace

Status RotationAlignmentParams::validate() const {
  if (coarsest_level < 1 || coarsest_level > 6)
    return Status::invalidArgument("rotation alignment: coarsest_level must be in [1, 6]");
  if (finest_level < 0 || finest_level > coarsest_level)
    return Status::invalidArgument("rotation alignment: finest_level must be in [0, coarsest]");
  if (iterations < 1) return Status::invalidArgument("rotation alignment: iterations must be >= 1");
  if (!(huber_grey > 0.0) || !std::isfinite(huber_grey))
    return Status::invalidArgument("rotation alignment: huber_grey must be > 0");
  if (!(search_deg >= 0.0 && search_deg <= 45.0))
    return Status::invalidArgument("rotation alignment: search_deg must be in [0, 45]");
  if (!(step_deg > 0.0 && step_deg <= 45.0))
    return Status::invalidArgument("rotation alignment: step_deg must be in (0, 45]");
  if (!(border_fraction >= 0.0 && border_fraction < 0.4))
    return Status::invalidArgument("rotation alignment: border_fraction must be in [0, 0.4)");
  return Status::ok();
}

RotationAlignment::RotationAlignment(const RotationAlignmentParams& params, int width, int height)
    : params_(params), width_(width), height_(height) {
  init_status_ = params.validate();
  if (init_status_ && ((width >> params.coarsest_level) < 8 || (height >> params.coarsest_level) < 8))
    init_status_ = Status::invalidArgument(
        "rotation alignment: the image is too small for the coarsest level (8x8 pixels at least)");
  if (!init_status_) return;
  descents_.reserve(8);
  prev_pyr_.resize(static_cast<std::size_t>(params.coarsest_level) + 1);
  cur_pyr_.resize(prev_pyr_.size());
  for (int l = 0; l <= params.coarsest_level; ++l) {
    prev_pyr_[static_cast<std::size_t>(l)].resize(width >> l, height >> l);
    cur_pyr_[static_cast<std::size_t>(l)].resize(width >> l, height >> l);
  }
}

void RotationAlignment::buildPyramid(ImageView<const std::uint8_t> img,
                                     std::vector<Image<float>>& pyr) const {
  Image<float>& l0 = pyr[0];
  for (int y = 0; y < height_; ++y) {
    const std::uint8_t* s = img.row(y);
    float* d = l0.view().row(y);
    for (int x = 0; x < width_; ++x) d[x] = static_cast<float>(s[x]);
  }
  for (std::size_t l = 1; l < pyr.size(); ++l) {
    const auto src = pyr[l - 1].view();
    const auto dst = pyr[l].view();
    for (int y = 0; y < dst.height; ++y) {
      const float* a = src.row(2 * y);
      const float* b = src.row(2 * y + 1);
      float* d = dst.row(y);
      for (int x = 0; x < dst.width; ++x)
        d[x] = 0.25f * (a[2 * x] + a[2 * x + 1] + b[2 * x] + b[2 * x + 1]);
    }
  }
}

double RotationAlignment::accumulate(int level, const PinholeCamera& camera,
                                     const Eigen::Matrix3d& R, double a, double b,
                                     Eigen::Matrix<double, 5, 5>* H, Eigen::Matrix<double, 5, 1>* g,
                                     double& overlap) const {
  const Image<float>& P = prev_pyr_[static_cast<std::size_t>(level)];
  const Image<float>& C = cur_pyr_[static_cast<std::size_t>(level)];
  const PinholeCamera cam = atLevel(camera, level);
  const int mx = static_cast<int>(params_.border_fraction * P.width()) + 1;
  const int my = static_cast<int>(params_.border_fraction * P.height()) + 1;
  const int total = std::max(1, (P.width() - 2 * mx) * (P.height() - 2 * my));
  const double k = params_.huber_grey;
  double sum = 0.0;
  int used = 0;
  for (int y = my; y < P.height() - my; ++y) {
    const float* prow = P.view().row(y);
    for (int x = mx; x < P.width() - mx; ++x) {
      const Eigen::Vector3d q =
          R * Eigen::Vector3d((x - cam.cx_px) / cam.fx_px, (y - cam.cy_px) / cam.fy_px, 1.0);
      if (!(q.z() > 1e-6)) continue;
      double I = 0, gx = 0, gy = 0;
      if (!sample(C, cam.fx_px * q.x() / q.z() + cam.cx_px, cam.fy_px * q.y() / q.z() + cam.cy_px,
                  I, gx, gy))
        continue;
      const double r = a * I + b - prow[x];
      const double ar = std::abs(r);
      sum += ar <= k ? 0.5 * r * r : k * (ar - 0.5 * k);
      ++used;
      if (H == nullptr) continue;
      // dr/dtheta = a [gx gy] dw/dq (-[q]x)
      const double iz = 1.0 / q.z();
      const Eigen::RowVector3d dwdq_u(cam.fx_px * iz, 0.0, -cam.fx_px * q.x() * iz * iz);
      const Eigen::RowVector3d dwdq_v(0.0, cam.fy_px * iz, -cam.fy_px * q.y() * iz * iz);
      const Eigen::RowVector3d dIdq = a * (gx * dwdq_u + gy * dwdq_v);
      Eigen::Matrix3d qx;
      qx << 0, -q.z(), q.y(), q.z(), 0, -q.x(), -q.y(), q.x(), 0;
      Eigen::Matrix<double, 1, 5> J;
      J.head<3>() = -dIdq * qx;
      J(3) = I;
      J(4) = 1.0;
      const double w = ar <= k ? 1.0 : k / ar;  // Huber weight
      H->noalias() += w * J.transpose() * J;
      g->noalias() += w * J.transpose() * r;
    }
  }
  overlap = static_cast<double>(used) / total;
  if (used < 50) return std::numeric_limits<double>::infinity();
  return sum / used;
}

double RotationAlignment::alignLevel(int level, const PinholeCamera& camera, Eigen::Matrix3d& R,
                                     double& a, double& b, double& overlap) const {
  double cost = std::numeric_limits<double>::infinity();
  for (int it = 0; it < params_.iterations; ++it) {
    Eigen::Matrix<double, 5, 5> H = Eigen::Matrix<double, 5, 5>::Zero();
    Eigen::Matrix<double, 5, 1> g = Eigen::Matrix<double, 5, 1>::Zero();
    cost = accumulate(level, camera, R, a, b, &H, &g, overlap);
    if (!std::isfinite(cost)) return cost;
    const Eigen::Matrix<double, 5, 1> dx = H.ldlt().solve(-g);
    if (!dx.allFinite()) return std::numeric_limits<double>::infinity();
    R = expSO3(dx.head<3>()) * R;
    a += dx(3);
    b += dx(4);
    if (dx.head<3>().norm() < 1e-6) break;
  }
  return cost;
}

Status RotationAlignment::process(ImageView<const std::uint8_t> prev,
                                  ImageView<const std::uint8_t> cur, const PinholeCamera& camera,
                                  const std::vector<Eigen::Matrix3d>& starts,
                                  RotationAlignmentResult& out) {
  if (!init_status_) return init_status_;
  if (prev.width != width_ || prev.height != height_ || cur.width != width_ ||
      cur.height != height_)
    return Status::invalidArgument("rotation alignment: image size differs from construction");
  if (starts.empty()) return Status::invalidArgument("rotation alignment: no starting rotation");
  buildPyramid(prev, prev_pyr_);
  buildPyramid(cur, cur_pyr_);
  // The descents' starts: the given rotations, then the best of the coarse grid around them.
  descents_.assign(starts.begin(), starts.end());
  if (params_.search_deg > 0.0) {
    const double deg = 3.14159265358979323846 / 180.0;
    const int n = static_cast<int>(std::floor(params_.search_deg / params_.step_deg + 1e-9));
    double grid_best = std::numeric_limits<double>::infinity();
    Eigen::Matrix3d R_best = starts[0];
    for (const Eigen::Matrix3d& R0 : starts)
      for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j) {
          const Eigen::Matrix3d R =
              expSO3(Eigen::Vector3d(i * params_.step_deg * deg, j * params_.step_deg * deg, 0.0)) *
              R0;
          double overlap = 0.0;
          double c = accumulate(params_.coarsest_level, camera, R, 1.0, 0.0, nullptr, nullptr,
                                overlap);
          if (overlap < 0.3) c = std::numeric_limits<double>::infinity();
          if (c < grid_best) {
            grid_best = c;
            R_best = R;
          }
        }
    if (std::isfinite(grid_best)) descents_.push_back(R_best);
  }
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < descents_.size(); ++s) {
    Eigen::Matrix3d R = descents_[s];
    double a = 1.0, b = 0.0, overlap = 0.0, cost = 0.0;
    for (int l = params_.coarsest_level; l >= params_.finest_level; --l)
      cost = alignLevel(l, camera, R, a, b, overlap);
    if (!(overlap >= 0.3) || !std::isfinite(cost) || !(cost < best)) continue;
    best = cost;
    out.R_cur_prev = R;
    out.rms_grey = std::sqrt(2.0 * cost);
    out.overlap = overlap;
    out.start = static_cast<int>(s);
  }
  if (!std::isfinite(best))
    return Status::failedPrecondition("rotation alignment: no start kept the images overlapping");
  return Status::ok();
}

}  // namespace svslam

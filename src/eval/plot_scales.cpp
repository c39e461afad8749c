#include "eval/plot_scales.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace svslam {

namespace {

double niceStep(double raw) {
  const double e = std::floor(std::log10(raw));
  const double base = std::pow(10.0, e);
  const double f = raw / base;
  const double nice = f < 1.5 ? 1.0 : f < 3.0 ? 2.0 : f < 7.0 ? 5.0 : 10.0;
  return nice * base;
}

// The next smaller step of the 1-2-5 sequence.
double smallerStep(double step) {
  const double e = std::floor(std::log10(step) + 1e-9);
  const double f = step / std::pow(10.0, e);
  if (f > 4.5) return 2.0 * std::pow(10.0, e);
  if (f > 1.5) return std::pow(10.0, e);
  return 0.5 * std::pow(10.0, e);
}

std::vector<double> multiples(double lo, double hi, double step) {
  std::vector<double> v;
  const double first = std::ceil(lo / step - 1e-9);
  for (double i = first;; i += 1.0) {
    const double t = i * step;
    if (t > hi + 1e-9 * step) break;
    v.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
    if (v.size() > 1000) break;
  }
  return v;
}

const char* kAxisNames[3] = {"x", "y", "z"};

std::string axisName(const Eigen::Vector3d& a) {
  for (int i = 0; i < 3; ++i)
    if (std::abs(std::abs(a[i]) - 1.0) < 1e-9)
      return std::string(a[i] < 0 ? "-" : "") + kAxisNames[i];
  return "";
}

}  // namespace

Ticks niceTicks(double lo, double hi, int target) {
  Ticks t;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi)) return t;
  target = std::max(target, 2);
  t.step = niceStep((hi - lo) / (target - 1));
  t.values = multiples(lo, hi, t.step);
  for (int k = 0; k < 8 && t.values.size() < 2; ++k) {
    t.step = smallerStep(t.step);
    t.values = multiples(lo, hi, t.step);
  }
  t.decimals = std::max(0, static_cast<int>(-std::floor(std::log10(t.step) + 1e-9)));
  return t;
}

std::string tickLabel(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", std::clamp(decimals, 0, 12), v);
  std::string s = buf;
  if (s.size() > 1 && s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

Result<Ellipse2> covarianceEllipse(const Eigen::Matrix2d& C, double k) {
  if (!C.allFinite()) return Status::invalidArgument("covariance has a non-finite entry");
  const double scale = C.cwiseAbs().maxCoeff();
  if (std::abs(C(0, 1) - C(1, 0)) > 1e-6 * std::max(scale, 1e-300))
    return Status::invalidArgument("covariance is not symmetric");
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  const Eigen::Vector2d lambda = es.eigenvalues();  // ascending
  if (lambda[0] < -1e-12 * std::max(scale, 1e-300))
    return Status::invalidArgument("covariance is not positive semi-definite");
  Ellipse2 e;
  e.a = k * std::sqrt(std::max(lambda[1], 0.0));
  e.b = k * std::sqrt(std::max(lambda[0], 0.0));
  const Eigen::Vector2d major = es.eigenvectors().col(1);
  double angle = std::atan2(major.y(), major.x());
  if (angle <= -M_PI / 2) angle += M_PI;
  if (angle > M_PI / 2) angle -= M_PI;
  e.angle_rad = angle;
  return e;
}

std::vector<Eigen::Vector2d> ellipsePoints(const Eigen::Vector2d& c, const Ellipse2& e, int n) {
  std::vector<Eigen::Vector2d> pts;
  const double ca = std::cos(e.angle_rad), sa = std::sin(e.angle_rad);
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * M_PI * i / n;
    const double x = e.a * std::cos(t), y = e.b * std::sin(t);
    pts.emplace_back(c.x() + ca * x - sa * y, c.y() + sa * x + ca * y);
  }
  return pts;
}

Result<HorizontalFrame> horizontalFrame(const Eigen::Vector3d& gravity) {
  const double n = gravity.norm();
  if (!gravity.allFinite() || !(n > 0))
    return Status::invalidArgument("gravity direction must be finite and non-zero");
  const Eigen::Vector3d g = gravity / n;
  HorizontalFrame f;
  f.up = -g;
  const double cos1 = std::cos(M_PI / 180.0);
  int aligned = -1;
  for (int i = 0; i < 3; ++i)
    if (std::abs(g[i]) >= cos1) aligned = i;
  if (aligned >= 0) {
    f.up = Eigen::Vector3d::Unit(aligned) * (g[aligned] > 0 ? -1.0 : 1.0);
    f.u = Eigen::Vector3d::Unit(aligned == 0 ? 1 : 0);
    f.v = f.up.cross(f.u);
    f.u_name = axisName(f.u);
    f.v_name = axisName(f.v);
    f.up_name = axisName(f.up);
    return f;
  }
  const double cos30 = std::cos(M_PI / 6.0);
  for (int j = 0; j < 3; ++j) {
    if (std::abs(g[j]) >= cos30) continue;
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(j);
    f.u = (e - e.dot(g) * g).normalized();
    break;
  }
  f.v = f.up.cross(f.u);
  f.u_name = "u";
  f.v_name = "v";
  f.up_name = "up";
  return f;
}

}  // namespace svslam

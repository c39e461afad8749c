#pragma once
// The numbers behind svslam's plots (svslam plot): axis ticks, 2-sigma covariance ellipses and
// the horizontal frame of a trajectory given the gravity direction. Pure math, no drawing.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/status.hpp"

namespace svslam {

// Tick positions on [lo, hi]: the multiples of step = {1, 2, 5} x 10^k that lie in the range,
// step chosen so that there are about `target` of them (at least 2 when lo < hi). An empty or
// degenerate range (lo >= hi, or non-finite) gives no tick.
struct Ticks {
  std::vector<double> values;
  double step = 0;
  int decimals = 0;  // enough decimals to tell neighbouring ticks apart
};
Ticks niceTicks(double lo, double hi, int target = 6);

// Tick label: `v` with `decimals` decimals, "-0" written as "0".
std::string tickLabel(double v, int decimals);

// The ellipse {x : (x - c)^T C^-1 (x - c) = k^2} of a 2x2 covariance C (symmetric): semi-axes
// a = k sqrt(lambda_max), b = k sqrt(lambda_min) along the eigenvectors, angle_rad of the major
// axis from the first coordinate axis towards the second, in (-pi/2, pi/2]. k = 2 gives the
// plain 2-sigma ellipse (probability 1 - exp(-2) = 86.5 % for a 2-D Gaussian; 95 % would be
// k = 2.448). Error when C has a non-finite entry, is not symmetric (relative 1e-6), or has a
// negative eigenvalue beyond rounding (-1e-12 relative to the largest); tiny negative
// eigenvalues count as 0.
struct Ellipse2 {
  double a = 0, b = 0;  // semi-axes, a >= b >= 0, units of sqrt(C)
  double angle_rad = 0;
};
Result<Ellipse2> covarianceEllipse(const Eigen::Matrix2d& C, double k = 2.0);

// `n` points on the ellipse centred at c (closed: the last one is not repeated).
std::vector<Eigen::Vector2d> ellipsePoints(const Eigen::Vector2d& c, const Ellipse2& e, int n);

// The plotting frame of a world frame with gravity direction g (any length, non-zero): the
// horizontal axes u, v (unit, orthogonal to g) and up = -g / |g|, right-handed (u x v = up), so
// that the top view (u to the right, v up the page) is seen from above, not mirrored. When g is
// within 1 degree of a coordinate axis, u and v are coordinate axes with names such as "x" or
// "-y" (KITTI, g = +y: u = x, v = z; a down-looking camera, g = +z: u = x, v = -y); otherwise
// u is the horizontal projection of the first coordinate axis not within 30 degrees of g,
// named "u", and v "v". The altitude of a point p is up . p.
struct HorizontalFrame {
  Eigen::Vector3d u = Eigen::Vector3d::UnitX(), v = Eigen::Vector3d::UnitY(),
                  up = Eigen::Vector3d::UnitZ();
  std::string u_name, v_name, up_name;  // e.g. "x", "z", "-y"
};
Result<HorizontalFrame> horizontalFrame(const Eigen::Vector3d& gravity);

}  // namespace svslam

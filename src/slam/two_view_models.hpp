#pragma once
// The two models of the two-view start (slam/two_view_initializer.hpp) fitted and scored on
// point correspondences x0 <-> x1 in normalised image coordinates (K^-1 applied):
//  - essential matrix E (8-point on Hartley-normalised points, then projected onto singular
//    values (1, 1, 0)): x1^T E x0 = 0;
//  - homography H (DLT on Hartley-normalised points): x1 ~ H x0.
// Scores as ORB-SLAM's (Mur-Artal et al. 2015, sec. IV; the chi-square tests and score are
// stated in slam/two_view_initializer.hpp); k = f^2 / sigma^2 turns squared normalised errors
// into chi-square values.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace svslam::two_view {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

inline Vector3d hom(const Vector2d& x) { return {x.x(), x.y(), 1.0}; }

// Hartley normalisation: xn = s (x - c), mean |xn| = sqrt(2). Returns T, (xn, 1) = T (x, 1).
Matrix3d normalisePoints(const std::vector<Vector2d>& x, std::vector<Vector2d>& xn);

// From the normalised points n0/n1 at idx[0..m) with their normalisations T0/T1; false when
// the fit is degenerate.
bool fitEssential(const std::vector<Vector2d>& n0, const std::vector<Vector2d>& n1, const int* idx,
                  int m, const Matrix3d& T0, const Matrix3d& T1, Matrix3d& E);
bool fitHomography(const std::vector<Vector2d>& n0, const std::vector<Vector2d>& n1, const int* idx,
                   int m, const Matrix3d& T0, const Matrix3d& T1, Matrix3d& H);

// The model's score over every correspondence; in[i] = 1 for an inlier in both directions.
double scoreEssential(const Matrix3d& E, const std::vector<Vector2d>& x0,
                      const std::vector<Vector2d>& x1, double k, std::vector<std::uint8_t>& in);
double scoreHomography(const Matrix3d& H, const std::vector<Vector2d>& x0,
                       const std::vector<Vector2d>& x1, double k, std::vector<std::uint8_t>& in);

}  // namespace svslam::two_view

#include "slam/two_view_models.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <limits>

namespace svslam::two_view {
namespace {

using Mat9 = Eigen::Matrix<double, 9, 9>;
using Vec9 = Eigen::Matrix<double, 9, 1>;

constexpr double kChi2E = 3.841;     // chi-square, 1 dof, 95 %: epipolar distance
constexpr double kChi2H = 5.991;     // chi-square, 2 dof, 95 %: transfer error
constexpr double kScoreCap = 5.991;  // score of a perfect point, per direction (both models)

// The unit vector minimising |A v| given M = A^T A: the eigenvector of the smallest eigenvalue.
Matrix3d nullMatrix(const Mat9& M) {
  const Eigen::SelfAdjointEigenSolver<Mat9> eig(M);
  const Vec9 v = eig.eigenvectors().col(0);
  Matrix3d F;
  F << v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7), v(8);
  return F;
}

double transferChi2(const Matrix3d& H, const Vector2d& from, const Vector2d& to, double k) {
  const Vector3d p = H * hom(from);
  if (!(std::abs(p.z()) > 0)) return std::numeric_limits<double>::infinity();
  return (p.head<2>() / p.z() - to).squaredNorm() * k;
}

}  // namespace

// Hartley normalisation: xn = s (x - c), mean |xn| = sqrt(2). Returns T, (xn, 1) = T (x, 1).
Matrix3d normalisePoints(const std::vector<Vector2d>& x, std::vector<Vector2d>& xn) {
  const double n = static_cast<double>(x.size());
  Vector2d c = Vector2d::Zero();
  for (const Vector2d& p : x) c += p;
  c /= n;
  double d = 0;
  for (const Vector2d& p : x) d += (p - c).norm();
  d /= n;
  const double s = d > 1e-12 ? std::sqrt(2.0) / d : 1.0;
  xn.resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) xn[i] = s * (x[i] - c);
  Matrix3d T;
  T << s, 0, -s * c.x(), 0, s, -s * c.y(), 0, 0, 1;
  return T;
}

// Essential matrix from the normalised points idx[0..m): X1n^T Fn X0n = 0, E = T1^T Fn T0
// projected onto singular values (1, 1, 0).
bool fitEssential(const std::vector<Vector2d>& n0, const std::vector<Vector2d>& n1, const int* idx,
                  int m, const Matrix3d& T0, const Matrix3d& T1, Matrix3d& E) {
  Mat9 M = Mat9::Zero();
  for (int k = 0; k < m; ++k) {
    const Vector3d a = hom(n0[idx[k]]), b = hom(n1[idx[k]]);
    Vec9 row;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) row(3 * i + j) = b(i) * a(j);
    M.noalias() += row * row.transpose();
  }
  const Matrix3d Ed = T1.transpose() * nullMatrix(M) * T0;
  const Eigen::JacobiSVD<Matrix3d> svd(Ed, Eigen::ComputeFullU | Eigen::ComputeFullV);
  E = svd.matrixU() * Vector3d(1, 1, 0).asDiagonal() * svd.matrixV().transpose();
  return E.allFinite() && svd.singularValues()(1) > 0;
}

// Homography from the normalised points idx[0..m) (DLT): X1n ~ Hn X0n, H = T1^-1 Hn T0.
bool fitHomography(const std::vector<Vector2d>& n0, const std::vector<Vector2d>& n1, const int* idx,
                   int m, const Matrix3d& T0, const Matrix3d& T1, Matrix3d& H) {
  Mat9 M = Mat9::Zero();
  for (int k = 0; k < m; ++k) {
    const Vector3d a = hom(n0[idx[k]]);
    const Vector2d& b = n1[idx[k]];
    Vec9 r1, r2;
    r1 << -a, Vector3d::Zero(), b.x() * a;
    r2 << Vector3d::Zero(), -a, b.y() * a;
    M.noalias() += r1 * r1.transpose() + r2 * r2.transpose();
  }
  const Matrix3d T1inv = T1.inverse();
  H = T1inv * nullMatrix(M) * T0;
  const double det = H.determinant();
  return H.allFinite() && std::abs(det) > 1e-12 * std::pow(H.norm(), 3);
}

double scoreEssential(const Matrix3d& E, const std::vector<Vector2d>& x0,
                      const std::vector<Vector2d>& x1, double k, std::vector<std::uint8_t>& in) {
  double score = 0;
  for (std::size_t i = 0; i < x0.size(); ++i) {
    const Vector3d a = hom(x0[i]), b = hom(x1[i]);
    const Vector3d l1 = E * a, l0 = E.transpose() * b;
    const double num2 = b.dot(l1) * b.dot(l1);
    const double chi1 = num2 / l1.head<2>().squaredNorm() * k;
    const double chi0 = num2 / l0.head<2>().squaredNorm() * k;
    bool ok = true;
    for (double chi : {chi1, chi0}) {
      if (chi <= kChi2E) {
        score += kScoreCap - chi;
      } else {
        ok = false;  // also NaN (a degenerate line)
      }
    }
    in[i] = ok ? 1 : 0;
  }
  return score;
}

double scoreHomography(const Matrix3d& H, const std::vector<Vector2d>& x0,
                       const std::vector<Vector2d>& x1, double k, std::vector<std::uint8_t>& in) {
  const Matrix3d Hinv = H.inverse();
  double score = 0;
  for (std::size_t i = 0; i < x0.size(); ++i) {
    bool ok = true;
    for (double chi : {transferChi2(H, x0[i], x1[i], k), transferChi2(Hinv, x1[i], x0[i], k)}) {
      if (chi <= kChi2H) {
        score += kScoreCap - chi;
      } else {
        ok = false;
      }
    }
    in[i] = ok ? 1 : 0;
  }
  return score;
}

}  // namespace svslam::two_view

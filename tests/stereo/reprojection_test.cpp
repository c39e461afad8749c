// Reprojection: geometry against the triangulation formulas, the covariance against a numeric
// Jacobian and against Monte Carlo sampling of (u, v, d).
#include "stereo/reprojection.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace svslam {
namespace {

StereoCalibration calib() {
  StereoCalibration c;
  c.f_px = 700.0;
  c.cx_px = 320.0;
  c.cy_px = 240.0;
  c.baseline_m = 0.5;
  c.width = 640;
  c.height = 480;
  return c;
}

TEST(Reprojection, PointMatchesTriangulationAndDepthSigma) {
  const auto c = calib();
  const StereoPoint p = reprojectPixel(c, 400.0, 100.0, 35.0, 0.2, 0.0);
  const double z = 700.0 * 0.5 / 35.0;
  EXPECT_NEAR(p.p_cam.z(), z, 1e-12);
  EXPECT_NEAR(p.p_cam.x(), (400.0 - 320.0) * z / 700.0, 1e-12);
  EXPECT_NEAR(p.p_cam.y(), (100.0 - 240.0) * z / 700.0, 1e-12);
  // sigma_z = z^2 sigma_d / (f b)
  EXPECT_NEAR(std::sqrt(p.cov(2, 2)), z * z * 0.2 / (700.0 * 0.5), 1e-12);
  EXPECT_TRUE(p.cov.isApprox(p.cov.transpose()));
}

TEST(Reprojection, CovarianceMatchesNumericJacobian) {
  const auto c = calib();
  const double u = 123.0, v = 411.0, d = 17.5, sd = 0.3, suv = 0.5;
  const StereoPoint p = reprojectPixel(c, u, v, d, sd, suv);
  Eigen::Matrix3d J;
  const double h = 1e-6;
  const double in[3] = {u, v, d};
  for (int k = 0; k < 3; ++k) {
    double a[3] = {in[0], in[1], in[2]}, b[3] = {in[0], in[1], in[2]};
    a[k] += h;
    b[k] -= h;
    J.col(k) = (reprojectPixel(c, a[0], a[1], a[2], 0, 0).p_cam -
                reprojectPixel(c, b[0], b[1], b[2], 0, 0).p_cam) /
               (2 * h);
  }
  const Eigen::Matrix3d expected =
      J * Eigen::Vector3d(suv * suv, suv * suv, sd * sd).asDiagonal() * J.transpose();
  EXPECT_TRUE(p.cov.isApprox(expected, 1e-6)) << p.cov << "\n\n" << expected;
}

TEST(Reprojection, CovarianceMatchesMonteCarloAtSmallErrors) {
  const auto c = calib();
  const double u = 500.0, v = 300.0, d = 40.0, sd = 0.1, suv = 0.3;
  const StereoPoint p = reprojectPixel(c, u, v, d, sd, suv);
  std::mt19937 rng(42);
  std::normal_distribution<double> n(0.0, 1.0);
  const int N = 20000;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> s(N);
  for (auto& q : s) {
    q = reprojectPixel(c, u + suv * n(rng), v + suv * n(rng), d + sd * n(rng), 0, 0).p_cam;
    mean += q;
  }
  mean /= N;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& q : s) cov += (q - mean) * (q - mean).transpose();
  cov /= (N - 1);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(std::sqrt(cov(i, i)) / std::sqrt(p.cov(i, i)), 1.0, 0.03) << i;
}

TEST(Reprojection, MapSkipsInvalidAndChecksInputs) {
  auto c = calib();
  c.width = 4;
  c.height = 2;
  ImageF32 d(4, 2), s(4, 2);
  const float inf = std::numeric_limits<float>::infinity();
  float dv[8] = {10, inf, 0.1f, 20, 30, 40, std::nanf(""), 50};
  for (int i = 0; i < 8; ++i) {
    d(i % 4, i / 4) = dv[i];
    s(i % 4, i / 4) = 0.5f;
  }
  std::vector<StereoPoint> pts;
  ASSERT_TRUE(reprojectDisparity(d.cview(), s.cview(), c, ReprojectionParams{}, pts).isOk());
  EXPECT_EQ(pts.size(), 5u);  // inf, below min disparity, NaN skipped
  for (const auto& p : pts) EXPECT_TRUE(p.p_cam.allFinite() && p.cov.allFinite());
  auto bad = c;
  bad.f_px = std::nan("");
  EXPECT_FALSE(reprojectDisparity(d.cview(), s.cview(), bad, ReprojectionParams{}, pts).isOk());
  ImageF32 small(3, 2);
  EXPECT_FALSE(reprojectDisparity(small.cview(), s.cview(), c, ReprojectionParams{}, pts).isOk());
}

}  // namespace
}  // namespace svslam

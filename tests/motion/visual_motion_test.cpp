// Visual motion estimation: exact recovery, outlier rejection, seeded RANSAC, and a Monte Carlo
// check that the propagated covariance matches the empirical errors (NEES in the chi-square
// 95 % band).
#include "motion/visual_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stereo/reprojection.hpp"

namespace svslam {
namespace {

StereoCalibration calib() { return {700.0, 320.0, 240.0, 0.5, 640, 480}; }

Eigen::Isometry3d motion() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = expSO3(Eigen::Vector3d(0.02, -0.05, 0.01));
  T.translation() = Eigen::Vector3d(0.3, -0.1, 1.2);
  return T;
}

// Stereo-like covariance of a point (from its pixel, disparity sigma 0.2 px, 0.5 px image plane).
Eigen::Matrix3d stereoCov(const Eigen::Vector3d& p) {
  const auto c = calib();
  const double u = c.f_px * p.x() / p.z() + c.cx_px, v = c.f_px * p.y() / p.z() + c.cy_px;
  const double d = c.f_px * c.baseline_m / p.z();
  return reprojectPixel(c, u, v, d, 0.2, 0.5).cov;
}

std::vector<Eigen::Vector3d> scene(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> x(-6, 6), y(-3, 3), z(5, 25);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < n; ++i) pts.emplace_back(x(rng), y(rng), z(rng));
  return pts;
}

Eigen::Vector3d sample(const Eigen::Vector3d& mean, const Eigen::Matrix3d& cov, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  const Eigen::Matrix3d L = cov.llt().matrixL();
  return mean + L * Eigen::Vector3d(n(rng), n(rng), n(rng));
}

std::vector<PointPair> noisyPairs(const std::vector<Eigen::Vector3d>& pts,
                                  const Eigen::Isometry3d& T, std::mt19937& rng, bool noise) {
  std::vector<PointPair> pairs;
  for (const auto& X : pts) {
    PointPair p;
    p.cov_prev = stereoCov(X);
    p.cov_cur = stereoCov(T * X);
    p.p_prev = noise ? sample(X, p.cov_prev, rng) : X;
    p.p_cur = noise ? sample(T * X, p.cov_cur, rng) : Eigen::Vector3d(T * X);
    pairs.push_back(p);
  }
  return pairs;
}

TEST(VisualMotion, RecoversExactMotionWithoutNoise) {
  std::mt19937 rng(1);
  const auto pairs = noisyPairs(scene(40, rng), motion(), rng, false);
  VisualMotion vm(VisualMotionParams{});
  VisualMotionResult r;
  ASSERT_TRUE(vm.process(pairs, r).isOk());
  EXPECT_TRUE(r.T_cur_prev.matrix().isApprox(motion().matrix(), 1e-9));
  EXPECT_EQ(r.used, 40);
}

TEST(VisualMotion, PropagatedCovarianceMatchesMonteCarloNees) {
  std::mt19937 rng(7);
  const auto pts = scene(60, rng);
  const Eigen::Isometry3d T = motion();
  VisualMotionParams params;
  params.max_point_sigma_m = 10.0;
  VisualMotion vm(params);
  const int runs = 300;
  double nees_sum = 0;
  for (int k = 0; k < runs; ++k) {
    VisualMotionResult r;
    ASSERT_TRUE(vm.process(noisyPairs(pts, T, rng, true), r).isOk());
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = logSO3(T.linear() * r.T_cur_prev.linear().transpose());
    e.tail<3>() = T.translation() - r.T_cur_prev.translation();
    nees_sum += e.dot(r.covariance.ldlt().solve(e));
  }
  const double mean_nees = nees_sum / runs;
  // chi2 with 6 * 300 dof: 95 % band of the mean [5.61, 6.39].
  std::printf("mean NEES over %d runs: %.3f (band 5.61 .. 6.39)\n", runs, mean_nees);
  EXPECT_GT(mean_nees, 5.61);
  EXPECT_LT(mean_nees, 6.39);
}

TEST(VisualMotion, RejectsGrossOutliers) {
  std::mt19937 rng(3);
  auto pairs = noisyPairs(scene(80, rng), motion(), rng, true);
  std::uniform_real_distribution<double> off(-3, 3);
  for (std::size_t i = 0; i < pairs.size(); i += 5)
    pairs[i].p_cur += Eigen::Vector3d(off(rng), off(rng), 2 + off(rng));
  for (bool ransac : {false, true}) {
    VisualMotionParams p;
    p.ransac = ransac;
    VisualMotion vm(p);
    VisualMotionResult r;
    ASSERT_TRUE(vm.process(pairs, r).isOk());
    EXPECT_LT((r.T_cur_prev.translation() - motion().translation()).norm(), 0.05) << ransac;
    int flagged = 0;
    for (std::size_t i = 0; i < pairs.size(); i += 5) flagged += r.inlier[i] == 0;
    EXPECT_GE(flagged, 15) << ransac;  // most of the 16 outliers are rejected
  }
}

TEST(VisualMotion, SeededRansacIsDeterministic) {
  std::mt19937 rng(5);
  const auto pairs = noisyPairs(scene(50, rng), motion(), rng, true);
  VisualMotionParams p;
  p.ransac = true;
  p.seed = 42;
  VisualMotionResult a, b;
  VisualMotion(p).process(pairs, a);
  VisualMotion(p).process(pairs, b);
  EXPECT_EQ(a.T_cur_prev.matrix(), b.T_cur_prev.matrix());
  EXPECT_EQ(a.inlier, b.inlier);
}

TEST(VisualMotion, BadInputIsAnErrorNotANaN) {
  std::mt19937 rng(9);
  auto pairs = noisyPairs(scene(4, rng), motion(), rng, false);
  VisualMotion vm(VisualMotionParams{});
  VisualMotionResult r;
  EXPECT_EQ(vm.process(pairs, r).code(), StatusCode::kFailedPrecondition);  // fewer than 6
  pairs = noisyPairs(scene(20, rng), motion(), rng, false);
  for (auto& p : pairs) p.p_prev.x() = std::nan("");
  EXPECT_FALSE(vm.process(pairs, r).isOk());
  VisualMotionParams bad;
  bad.k_start = 2;
  EXPECT_FALSE(VisualMotion(bad).initStatus().isOk());
}

}  // namespace
}  // namespace svslam

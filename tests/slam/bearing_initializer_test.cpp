// Bearing-only landmark initialisation (seed 003 section 5): the sampled Gaussian against an
// independent numerical integration of the same density, its consistency in space, the refusal
// of views too parallel, bad input, determinism.
#include "slam/bearing_initializer.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <random>
#include <vector>

namespace svslam {
namespace {

using Eigen::Matrix2d;
using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kDeg = M_PI / 180.0;

BearingView<2> view2(const Vector2d& o, const Vector2d& target, double sigma, double noise = 0) {
  const Vector2d v = target - o;
  const double a = std::atan2(v.y(), v.x()) + noise;
  return {o, Vector2d(std::cos(a), std::sin(a)), sigma};
}

// Two views in the plane: mean and covariance of the samples against those of
// p1 p2 (seed 003 eq. 14 for each) integrated on a fine grid, a reference that shares nothing
// with the sampler but the density formula.
TEST(BearingInitializer, PlaneMatchesGridIntegration) {
  BearingInitParams params;
  params.r_min_m = 0.03;
  params.r_max_m = 1.2;
  params.num_samples = 40000;
  params.max_draws = 10000000;
  params.min_parallax_sigmas = 8;  // the views below differ by 11 sigma
  BearingInitializer<2> init(params);
  ASSERT_TRUE(init.initStatus());
  const double sigma = 2 * kDeg;
  const std::vector<BearingView<2>> views = {view2({0, 0}, {0.35, 0.3}, sigma, 0.01),
                                             view2({0.2, 0}, {0.35, 0.3}, sigma, -0.02)};
  BearingEstimate<2> est;
  ASSERT_TRUE(init.process(views, 7, est));
  ASSERT_EQ(est.outcome, BearingEstimate<2>::Outcome::kInitialised);

  // Grid: 800 x 800 cells over +-8 linearised sigmas around the sampled mean.
  const double half = 8 * std::sqrt(est.cov_m2.eigenvalues().real().maxCoeff());
  const int n = 800;
  double w_sum = 0;
  Vector2d mean = Vector2d::Zero();
  Matrix2d second = Matrix2d::Zero();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const Vector2d x = est.mean_m + Vector2d(-half + (i + 0.5) * 2 * half / n,
                                               -half + (j + 0.5) * 2 * half / n);
      const double lp = init.logDensity(views, x);
      if (!std::isfinite(lp)) continue;
      const double w = std::exp(lp);
      w_sum += w;
      mean += w * x;
      second += w * x * x.transpose();
    }
  }
  mean /= w_sum;
  const Matrix2d cov = second / w_sum - mean * mean.transpose();
  // Sampling error of the mean: sqrt(cov / N); allow 4 of them.
  const Vector2d d = est.mean_m - mean;
  EXPECT_LT(d.dot(cov.inverse() * d), 16.0 / params.num_samples) << d.transpose();
  EXPECT_NEAR(est.cov_m2(0, 0), cov(0, 0), 0.04 * cov(0, 0));
  EXPECT_NEAR(est.cov_m2(1, 1), cov(1, 1), 0.04 * cov(1, 1));
  EXPECT_NEAR(est.cov_m2(0, 1), cov(0, 1), 0.04 * std::sqrt(cov(0, 0) * cov(1, 1)));
  EXPECT_LT(est.draws, params.max_draws);
}

// In space: over 300 random geometries (two or three views, true landmark 5-40 m away, 1-3
// mrad bearing errors), the landmark's NEES against its Gaussian has mean 3 (chi-square, 3
// dof) and 95 % of the runs fall below the 95 % quantile 7.81.
TEST(BearingInitializer, SpaceIsConsistent) {
  BearingInitParams params;
  params.num_samples = 2000;
  BearingInitializer<3> init(params);
  ASSERT_TRUE(init.initStatus());
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(0, 1);
  double nees_sum = 0, draws_sum = 0;
  int growths = 0;
  int runs = 0, inside = 0, waited = 0;
  for (int run = 0; run < 300; ++run) {
    const Vector3d m(u(rng) * 10 - 5, u(rng) * 6 - 3, 5 + 35 * u(rng));
    const int k_views = 2 + run % 2;
    std::vector<BearingView<3>> views;
    for (int k = 0; k < k_views; ++k) {
      const Vector3d o(2.0 * k + 0.3 * g(rng), 0.2 * g(rng), 0.5 * k * g(rng));
      const double sigma = (1 + 2 * u(rng)) * 1e-3;
      Vector3d d = (m - o).normalized();
      // Isotropic angular error: a perpendicular perturbation of sigma per axis.
      const Vector3d e1 = d.unitOrthogonal(), e2 = d.cross(e1);
      d = (d + sigma * g(rng) * e1 + sigma * g(rng) * e2).normalized();
      views.push_back({o, d, sigma});
    }
    BearingEstimate<3> est;
    const Status st = init.process(views, static_cast<std::uint64_t>(run), est);
    ASSERT_TRUE(st) << st.message();
    if (est.outcome != BearingEstimate<3>::Outcome::kInitialised) {
      ++waited;
      continue;
    }
    const Vector3d e = est.mean_m - m;
    const double nees = e.dot(est.cov_m2.inverse() * e);
    nees_sum += nees;
    draws_sum += est.draws;
    growths += est.growths;
    inside += nees < 7.81 ? 1 : 0;
    ++runs;
  }
  ASSERT_GT(runs, 200) << waited << " geometries waited";
  const double mean_nees = nees_sum / runs;
  std::printf("bearing init, space: %d runs (%d waited), mean NEES %.2f, %.1f %% below 7.81, "
              "%.0f draws a landmark, %d box growths\n",
              runs, waited, mean_nees, 100.0 * inside / runs, draws_sum / runs, growths);
  EXPECT_GT(mean_nees, 2.4);
  EXPECT_LT(mean_nees, 3.6);
  EXPECT_GE(inside, static_cast<int>(0.92 * runs));
}

TEST(BearingInitializer, ParallelViewsWait) {
  BearingInitializer<3> init(BearingInitParams{});
  const double sigma = 1e-3;
  // Moving straight at the landmark: the bearings are the same.
  std::vector<BearingView<3>> views = {
      {Vector3d(0, 0, 0), Vector3d(0, 0, 1), sigma},
      {Vector3d(0, 0, 1), Vector3d(0, 0.001, 1).normalized(), sigma}};
  BearingEstimate<3> est;
  ASSERT_TRUE(init.process(views, 0, est));
  EXPECT_EQ(est.outcome, BearingEstimate<3>::Outcome::kTooParallel);
  EXPECT_NEAR(est.parallax_rad, 0.001, 1e-6);
  // Diverging rays (intersection behind the observers): out of range.
  views = {{Vector3d(0, 0, 0), Vector3d(-0.1, 0, 1).normalized(), sigma},
           {Vector3d(1, 0, 0), Vector3d(0.1, 0, 1).normalized(), sigma}};
  ASSERT_TRUE(init.process(views, 0, est));
  EXPECT_EQ(est.outcome, BearingEstimate<3>::Outcome::kOutOfRange);
}

TEST(BearingInitializer, BadInputIsNamed) {
  BearingInitParams bad;
  bad.r_max_m = 0.1;
  EXPECT_FALSE(BearingInitializer<3>(bad).initStatus());
  bad = BearingInitParams{};
  bad.num_samples = 5;
  EXPECT_NE(BearingInitializer<3>(bad).initStatus().message().find("num_samples"),
            std::string::npos);
  BearingInitializer<3> init(BearingInitParams{});
  BearingEstimate<3> est;
  std::vector<BearingView<3>> views = {{Vector3d(0, 0, 0), Vector3d(0, 0, 1), 1e-3}};
  EXPECT_FALSE(init.process(views, 0, est));
  views.push_back({Vector3d(1, 0, 0), Vector3d(0, 0, 2), 1e-3});
  Status s = init.process(views, 0, est);
  EXPECT_NE(s.message().find("unit"), std::string::npos) << s.message();
  views[1].direction = Vector3d(0, 0, 1);
  views[1].sigma_rad = std::nan("");
  s = init.process(views, 0, est);
  EXPECT_NE(s.message().find("sigma"), std::string::npos) << s.message();
  views[1].origin_m.x() = std::nan("");
  EXPECT_FALSE(init.process(views, 0, est));
}

TEST(BearingInitializer, SameStreamSameResult) {
  BearingInitializer<3> a(BearingInitParams{}), b(BearingInitParams{});
  const std::vector<BearingView<3>> views = {
      {Vector3d(0, 0, 0), Vector3d(0.1, 0, 1).normalized(), 2e-3},
      {Vector3d(1, 0, 0), Vector3d(-0.02, 0, 1).normalized(), 2e-3}};
  BearingEstimate<3> ea, eb, ec;
  ASSERT_TRUE(a.process(views, 11, ea));
  ASSERT_TRUE(b.process(views, 11, eb));
  ASSERT_TRUE(b.process(views, 12, ec));
  ASSERT_EQ(ea.outcome, BearingEstimate<3>::Outcome::kInitialised);
  EXPECT_EQ(ea.mean_m, eb.mean_m);
  EXPECT_EQ(ea.cov_m2, eb.cov_m2);
  EXPECT_NE(ea.mean_m, ec.mean_m);
}

}  // namespace
}  // namespace svslam

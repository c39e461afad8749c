// SigmaModel: interpolation, validation, and the fit on synthetic samples whose true sigma is
// known (sigma = 0.1 + 2 / kappa, Gaussian errors).
#include "stereo/sigma_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace svslam {
namespace {

TEST(SigmaModel, InterpolatesAndClamps) {
  SigmaModel m;
  m.curvature = {1.0f, 3.0f};
  m.sigma_px = {1.0f, 0.5f};
  ASSERT_TRUE(m.validate().isOk());
  EXPECT_FLOAT_EQ(m.sigmaFor(0.0f), 1.0f);
  EXPECT_FLOAT_EQ(m.sigmaFor(std::nanf("")), 1.0f);
  EXPECT_FLOAT_EQ(m.sigmaFor(2.0f), 0.75f);
  EXPECT_FLOAT_EQ(m.sigmaFor(10.0f), 0.5f);
  EXPECT_TRUE(SigmaModel::defaultCensus().validate().isOk());
}

TEST(SigmaModel, RejectsBadTables) {
  SigmaModel m;
  EXPECT_FALSE(m.validate().isOk());
  m.curvature = {1.0f, 1.0f};
  m.sigma_px = {1.0f, 0.5f};
  EXPECT_FALSE(m.validate().isOk());  // not strictly increasing
  m.curvature = {1.0f, 2.0f};
  m.sigma_px = {0.5f, 1.0f};
  EXPECT_FALSE(m.validate().isOk());  // sigma increases
  m.sigma_px = {1.0f, std::nanf("")};
  EXPECT_FALSE(m.validate().isOk());
}

TEST(SigmaModel, FitRecoversKnownSigmaAndCoverage) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> uk(1.0f, 40.0f);
  std::normal_distribution<float> n(0.0f, 1.0f);
  auto truth = [](float k) { return 0.1f + 2.0f / k; };
  std::vector<float> kappa, err, k_test, e_test;
  for (int i = 0; i < 200000; ++i) {
    const float k = uk(rng);
    (i % 2 ? kappa : k_test).push_back(k);
    (i % 2 ? err : e_test).push_back(std::abs(truth(k) * n(rng)));
  }
  auto m = fitSigmaModel(kappa, err, 20);
  ASSERT_TRUE(m.isOk()) << m.status().message();
  // (Within a bin the steep 1/kappa mixes sigmas, so the check starts where bins are narrow.)
  for (float k : {6.0f, 10.0f, 30.0f}) EXPECT_NEAR(m->sigmaFor(k), truth(k), 0.1 * truth(k)) << k;
  EXPECT_NEAR(sigmaCoverage(*m, k_test, e_test), 0.6827, 0.02);
  EXPECT_FALSE(fitSigmaModel({1.0f}, {1.0f}, 2).isOk());  // too few samples
}

}  // namespace
}  // namespace svslam

// Honesty of sigma_d on real data: leave-one-scene-out over Middlebury v2 tsukuba, venus, teddy,
// cones and Middlebury 2006 aloe. For each scene, the curvature -> sigma table is fitted on the
// other four and the share of that scene's errors inside one sigma is measured. The mean must be
// about 68 % (0.62 .. 0.74), no scene outside 0.45 .. 0.85. Skipped when the data is absent.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "real_data.hpp"
#include "sigma_samples.hpp"
#include "stereo/sigma_model.hpp"

namespace svslam {
namespace {

using Samples = testing::SigmaSamples;

Samples samplesOf(const testing::CaseRun& run, std::size_t cap) {
  Samples all;
  const auto& gt = run.loaded.gt;
  for (int y = 0; y < gt.height(); ++y)
    for (int x = 0; x < gt.width(); ++x) {
      const float g = gt(x, y), d = run.result.disparity_px(x, y);
      if (!std::isfinite(g) || !(g > 0) || !std::isfinite(d)) continue;
      if (!run.loaded.mask.empty() && run.loaded.mask(x, y) == 0) continue;
      all.kappa.push_back(run.result.curvature(x, y));
      all.err.push_back(std::abs(d - g));
    }
  Samples out;  // even subsampling to at most `cap`, as svslam fit-sigma does
  const std::size_t n = all.kappa.size(), keep = std::min(n, cap);
  for (std::size_t j = 0; j < keep; ++j) {
    out.kappa.push_back(all.kappa[j * n / keep]);
    out.err.push_back(all.err[j * n / keep]);
  }
  return out;
}

TEST(SigmaCalibration, LeaveOneSceneOutCoverageIsAbout68Percent) {
  const std::vector<std::string>& scenes = testing::kSigmaScenes;
  if (const std::string missing = testing::missingSigmaScene(); !missing.empty())
    GTEST_SKIP() << "shared data absent: " << missing;
  std::vector<Samples> per_scene;
  for (const auto& c : scenes)
    per_scene.push_back(samplesOf(testing::runCase(c, DenseStereoParams{}), 100000));
  const std::vector<double> coverage = testing::heldOutCoverages(per_scene, 12);
  ASSERT_EQ(coverage.size(), scenes.size());
  double mean = 0;
  for (std::size_t h = 0; h < scenes.size(); ++h) {
    const double cov = coverage[h];
    std::printf("held-out %-24s coverage %.3f\n", scenes[h].c_str(), cov);
    EXPECT_GT(cov, 0.45) << scenes[h];
    EXPECT_LT(cov, 0.85) << scenes[h];
    mean += cov / static_cast<double>(scenes.size());
  }
  std::printf("mean held-out coverage %.3f\n", mean);
  EXPECT_NEAR(mean, 0.6827, 0.06);
  // The built-in model was fitted on all five: its coverage on them is about 68 %.
  const Samples all = testing::pooledSamples(per_scene);
  EXPECT_NEAR(sigmaCoverage(SigmaModel::defaultCensus(), all.kappa, all.err), 0.6827, 0.03);
}

}  // namespace
}  // namespace svslam

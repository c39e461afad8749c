// Honesty of the sparse matches' sigma_d on real data: the corners of each ground-truth case
// matched by StereoPointMatcher (default parameters), leave-one-scene-out over Middlebury v2
// tsukuba, venus, teddy, cones and Middlebury 2006 aloe. For each scene the curvature -> sigma
// table is fitted on the other four (8 equal-count bins) and the share of that scene's errors
// inside one sigma is measured. The mean must be about 68 % (0.6827 +- 0.06). Per scene the
// spread is wide (measured 0.43 .. 0.93: venus is planar and nearly noise-free, aloe a
// full-size JPEG; about 200-550 matches per scene), so each scene is only bounded to
// 0.35 .. 0.95. The built-in table (fitted on all five) must cover 68 % +- 0.03 of all.
// (KITTI stereo 2012 000070 is not used: fewer than 40 corners matched with LiDAR ground truth
// at their pixel.) Skipped when the data is absent.
#include <gtest/gtest.h>

#include <cstdio>

#include "../stereo/real_data.hpp"
#include "../stereo/sigma_samples.hpp"
#include "pipeline/tools/point_sigma_samples.hpp"
#include "stereo/sigma_model.hpp"

namespace svslam {
namespace {

using Samples = testing::SigmaSamples;

Samples samplesOf(const std::string& sub) {
  Samples s;
  auto info = drivers::findStereoGtCase(testing::dataDir() + "/" + sub, "nonocc", "");
  EXPECT_TRUE(info.isOk()) << info.status().message();
  if (!info) return s;
  auto c = cli::loadCase(*info, true, true);
  EXPECT_TRUE(c.isOk()) << c.status().message();
  if (!c) return s;
  const Status st =
      cli::collectPointSamples(*c, CornerParams{}, StereoMatchParams{}, s.kappa, s.err);
  EXPECT_TRUE(st.isOk()) << st.message();
  return s;
}

TEST(PointSigmaCalibration, LeaveOneSceneOutCoverageIsAbout68Percent) {
  const std::vector<std::string>& scenes = testing::kSigmaScenes;
  if (const std::string missing = testing::missingSigmaScene(); !missing.empty())
    GTEST_SKIP() << "shared data absent: " << missing;
  std::vector<Samples> per_scene;
  for (const auto& c : scenes) per_scene.push_back(samplesOf(c));
  const std::vector<double> coverage = testing::heldOutCoverages(per_scene, 8);
  ASSERT_EQ(coverage.size(), scenes.size());
  double mean = 0;
  for (std::size_t h = 0; h < scenes.size(); ++h) {
    const double cov = coverage[h];
    std::printf("held-out %-26s matches %5zu coverage %.3f\n", scenes[h].c_str(),
                per_scene[h].kappa.size(), cov);
    // Loose per-scene bounds: the scenes differ (aloe's JPEG errors are larger, venus's planar
    // texture gives the refined matches smaller errors than the others at the same curvature).
    EXPECT_GT(cov, 0.35) << scenes[h];
    EXPECT_LT(cov, 0.97) << scenes[h];
    mean += cov / static_cast<double>(scenes.size());
  }
  std::printf("mean held-out coverage %.3f\n", mean);
  EXPECT_NEAR(mean, 0.6827, 0.06);
  const Samples pooled = testing::pooledSamples(per_scene);
  const double all = sigmaCoverage(SigmaModel::defaultZnccPoints(), pooled.kappa, pooled.err);
  std::printf("built-in table coverage on all %zu matches %.3f\n", pooled.kappa.size(), all);
  EXPECT_NEAR(all, 0.6827, 0.03);
}

}  // namespace
}  // namespace svslam

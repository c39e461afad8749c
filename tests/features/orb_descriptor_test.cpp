// ORB descriptors and scales against known image transforms (cv::warpAffine, cv::resize):
// matching under rotation and scale, the Hamming distance, the seeded pattern.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <numbers>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <utility>

#include "features/fast_detector.hpp"
#include "features/orb_extractor.hpp"
#include "orb_test_support.hpp"

namespace svslam {
namespace {

using namespace orb_test;  // NOLINT: the shared fixtures

// ---- descriptor matching --------------------------------------------------------------------

struct MatchStats {
  int matches = 0, correct = 0;
  std::vector<double> scale_ratio;  // scale_a / scale_b of the correct matches
};

// Matches a -> b (ratio test 0.8) and checks each against M (a's level-0 px -> b's), counting
// only a-keypoints that land inside b at least 20 px from its border.
MatchStats matchUnder(const cv::Mat& a, const cv::Mat& b, const cv::Mat& M) {
  OrbParams p;
  const Features fa = extract(a, p), fb = extract(b, p);
  MatchStats st;
  for (const auto& [i, j] : matchRatio(fa, fb, 0.8)) {
    const auto& ka = fa.kp[static_cast<std::size_t>(i)];
    const auto& kb = fb.kp[static_cast<std::size_t>(j)];
    const cv::Point2d pb = apply(M, ka.x_px, ka.y_px);
    if (pb.x < 20 || pb.y < 20 || pb.x > b.cols - 21 || pb.y > b.rows - 21) continue;
    ++st.matches;
    if (std::hypot(kb.x_px - pb.x, kb.y_px - pb.y) <= 2.0) {
      ++st.correct;
      st.scale_ratio.push_back(ka.scale / kb.scale);
    }
  }
  return st;
}

TEST(OrbDescriptor, MatchesUnderRotationAndScale) {
  const cv::Mat a = texture(640, 480, 21);
  const cv::Mat M = cv::getRotationMatrix2D(cv::Point2f(319.5f, 239.5f), 30.0, 0.75);
  cv::Mat b;
  cv::warpAffine(a, b, M, a.size(), cv::INTER_AREA, cv::BORDER_CONSTANT, cv::Scalar(0));
  const MatchStats st = matchUnder(a, b, M);
  std::printf(
      "[descriptor] rotation 30 deg, scale 0.75: %d of %d ratio-test matches correct (%.1f%%)\n",
      st.correct, st.matches, 100.0 * st.correct / std::max(1, st.matches));
  EXPECT_GT(st.matches, 100);
  EXPECT_GE(st.correct, 0.7 * st.matches);
}

TEST(OrbDescriptor, MatchesTsukubaRotated) {
  const std::string path = std::string(SVSLAM_DATA_DIR) + "/middlebury_v2/tsukuba/imL.png";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
  const cv::Mat a = cv::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(a.empty());
  const cv::Mat M =
      cv::getRotationMatrix2D(cv::Point2f(a.cols / 2.0f - 0.5f, a.rows / 2.0f - 0.5f), 30.0, 0.75);
  cv::Mat b;
  cv::warpAffine(a, b, M, a.size(), cv::INTER_AREA, cv::BORDER_CONSTANT, cv::Scalar(0));
  const MatchStats st = matchUnder(a, b, M);
  std::printf("[descriptor] tsukuba, rotation 30 deg, scale 0.75: %d of %d correct (%.1f%%)\n",
              st.correct, st.matches, 100.0 * st.correct / std::max(1, st.matches));
  EXPECT_GT(st.matches, 30);
  EXPECT_GE(st.correct, 0.7 * st.matches);
}

TEST(OrbScale, HalvedImageHasHalfTheScale) {
  const cv::Mat a = texture(800, 600, 5);
  cv::Mat b;
  cv::resize(a, b, cv::Size(400, 300), 0, 0, cv::INTER_AREA);
  // Level-0 pixel centres: x_b = (x_a + 0.5) / 2 - 0.5.
  cv::Mat M = (cv::Mat_<double>(2, 3) << 0.5, 0, -0.25, 0, 0.5, -0.25);
  MatchStats st = matchUnder(a, b, M);
  ASSERT_GT(st.correct, 50);
  std::sort(st.scale_ratio.begin(), st.scale_ratio.end());
  const double median = st.scale_ratio[st.scale_ratio.size() / 2];
  const double q1 = st.scale_ratio[st.scale_ratio.size() / 4];
  const double q3 = st.scale_ratio[st.scale_ratio.size() * 3 / 4];
  std::printf(
      "[scale] 0.5x: %d correct matches of %d, scale ratio median %.3f (quartiles %.3f, "
      "%.3f)\n",
      st.correct, st.matches, median, q1, q3);
  EXPECT_NEAR(median, 2.0, 0.15);
  EXPECT_GT(q1, 1.6);
  EXPECT_LT(q3, 2.5);
}

TEST(OrbDescriptor, HammingDistanceCountsBits) {
  OrbDescriptor a, b;
  EXPECT_EQ(hammingDistance(a, b), 0);
  b.words = {~0ULL, 0, 1, 0x8000000000000001ULL};
  EXPECT_EQ(hammingDistance(a, b), 64 + 1 + 2);
  EXPECT_EQ(hammingDistance(b, b), 0);
  a.words = {~0ULL, ~0ULL, ~0ULL, ~0ULL};
  EXPECT_EQ(hammingDistance(a, OrbDescriptor{}), 256);
}

TEST(OrbDescriptor, PatternInsidePatchAndSeeded) {
  OrbExtractor ex(OrbParams{}, 64, 64);
  ASSERT_TRUE(ex.initStatus().isOk());
  ASSERT_EQ(ex.pattern().size(), 256u);
  for (const auto& p : ex.pattern()) {
    EXPECT_LE(p[0] * p[0] + p[1] * p[1], 15 * 15);
    EXPECT_LE(p[2] * p[2] + p[3] * p[3], 15 * 15);
    EXPECT_FALSE(p[0] == p[2] && p[1] == p[3]);
  }
  OrbParams other;
  other.pattern_seed = 99;
  OrbExtractor ex2(other, 64, 64);
  EXPECT_NE(ex.pattern(), ex2.pattern());
  EXPECT_EQ(ex.pattern(), OrbExtractor(OrbParams{}, 80, 70).pattern());
}

// ---- extractor behaviour --------------------------------------------------------------------

}  // namespace
}  // namespace svslam

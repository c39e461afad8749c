// ORB extractor against independent references: cv::FAST for the segment test and score, known
// image transforms (cv::warpAffine) for orientation; keypoint bookkeeping, determinism, bad input.
// Descriptor and scale tests: orb_descriptor_test.cpp.
#include "features/orb_extractor.hpp"

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
#include "orb_test_support.hpp"

namespace svslam {
namespace {

using namespace orb_test;  // NOLINT: the shared fixtures

// ---- FAST against OpenCV -------------------------------------------------------------------

void expectFastLikeOpenCv(const cv::Mat& m, int threshold) {
  const ImageU8 img = toImage(m);
  std::vector<FastCorner> mine;
  detectFastCorners(img.cview(), threshold, mine);
  std::vector<cv::KeyPoint> ref;
  cv::FAST(m, ref, threshold, false, cv::FastFeatureDetector::TYPE_9_16);
  std::set<std::pair<int, int>> a, b;
  for (const auto& c : mine) a.insert({c.x, c.y});
  for (const auto& k : ref) b.insert({static_cast<int>(k.pt.x), static_cast<int>(k.pt.y)});
  EXPECT_GT(b.size(), 100u);
  EXPECT_EQ(a.size(), mine.size());
  EXPECT_TRUE(a == b) << "threshold " << threshold << ": svslam " << a.size() << " corners, OpenCV "
                      << b.size();
  // Scores: OpenCV's response of the corners kept by its 3x3 suppression is the FAST score.
  cv::FAST(m, ref, threshold, true, cv::FastFeatureDetector::TYPE_9_16);
  int wrong = 0;
  for (const auto& k : ref) {
    const int s = fastCornerScore(img.cview(), static_cast<int>(k.pt.x), static_cast<int>(k.pt.y),
                                  FastMask::k9of16);
    wrong += s != static_cast<int>(k.response);
  }
  EXPECT_EQ(wrong, 0) << "of " << ref.size() << " scores";
}

TEST(OrbFast, MatchesOpenCvFastOnSyntheticTexture) {
  const cv::Mat m = texture(333, 241, 7);
  for (int t : {5, 12, 20, 40}) expectFastLikeOpenCv(m, t);
}

TEST(OrbFast, MatchesOpenCvFastOnTsukuba) {
  const std::string path = std::string(SVSLAM_DATA_DIR) + "/middlebury_v2/tsukuba/imL.png";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
  const cv::Mat m = cv::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(m.empty());
  for (int t : {10, 20, 30}) expectFastLikeOpenCv(m, t);
}

TEST(OrbFast, ScoreIsLargestThresholdStillCorner) {
  const cv::Mat m = texture(120, 90, 3);
  const ImageU8 img = toImage(m);
  const auto o = fastOffsets16(img.stride());
  for (int y = 3; y < 87; y += 2)
    for (int x = 3; x < 117; x += 2) {
      const int s = fastCornerScore(img.cview(), x, y, FastMask::k9of16);
      const std::uint8_t* p = img.row(y) + x;
      if (s >= 1) {
        EXPECT_TRUE(fastIsCorner16(p, o, s)) << x << "," << y;
      }
      EXPECT_FALSE(fastIsCorner16(p, o, s + 1)) << x << "," << y;
    }
  // A single bright pixel: every ring pixel is darker by 100, so the score is 99 for both masks.
  ImageU8 dot(9, 9);
  dot.fill(50);
  dot(4, 4) = 150;
  EXPECT_EQ(fastCornerScore(dot.cview(), 4, 4, FastMask::k5of8), 99);
  EXPECT_EQ(fastCornerScore(dot.cview(), 4, 4, FastMask::k9of16), 99);
  EXPECT_EQ(fastCornerScore(dot.cview(), 0, 4, FastMask::k5of8), 0);
}

// The branch-free score (what the detector uses) against the windowed reference with early exits
// (OpenCV's cornerScore scheme), on every pixel: random texture, a binary 0/255 pattern (the
// extremes of the 16-bit differences) and flat areas.
TEST(OrbFast, BranchlessScoreEqualsTheReferenceOnEveryPixel) {
  cv::Mat binary(64, 64, CV_8UC1);
  cv::randu(binary, 0, 2);
  binary *= 255;
  cv::Mat flat(32, 32, CV_8UC1, cv::Scalar(77));
  for (const cv::Mat& m : {texture(200, 150, 11), binary, flat}) {
    const ImageU8 img = toImage(m);
    const auto o16 = fastOffsets16(img.stride());
    const auto o8 = fastOffsets8(img.stride());
    int wrong16 = 0, wrong8 = 0;
    for (int y = 3; y < m.rows - 3; ++y)
      for (int x = 3; x < m.cols - 3; ++x) {
        const std::uint8_t* p = img.row(y) + x;
        wrong16 += fast_detail::scoreBranchless<16>(p, o16) != fast_detail::score<16>(p, o16);
        wrong8 += fast_detail::scoreBranchless<8>(p, o8) != fast_detail::score<8>(p, o8);
      }
    EXPECT_EQ(wrong16, 0);
    EXPECT_EQ(wrong8, 0);
  }
}

// ---- pyramid --------------------------------------------------------------------------------

TEST(OrbPyramid, LayerSizesFollowTable1AndMapCentres) {
  const int w = 301, h = 203;
  OrbExtractor ex(OrbParams{}, w, h);
  ASSERT_TRUE(ex.initStatus().isOk());
  ASSERT_EQ(ex.numLayers(), 8);
  const double scales[8] = {1, 1.5, 2, 3, 4, 6, 8, 12};
  // Ramp I = 10 + 0.4 x + 0.3 y: area resampling keeps a linear image linear, so a layer pixel
  // holds the ramp at its centre X0 = (x + 0.5) t - 0.5 (up to rounding at each stage).
  ImageU8 img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img(x, y) = static_cast<std::uint8_t>(std::lround(10 + 0.4 * x + 0.3 * y));
  std::vector<OrbKeypoint> kp;
  std::vector<OrbDescriptor> d;
  ASSERT_TRUE(ex.process(img.cview(), kp, d).isOk());
  for (int k = 0; k < 8; ++k) {
    const double t = scales[k];
    EXPECT_DOUBLE_EQ(OrbExtractor::layerScale(k), t);
    const auto l = ex.layer(k);
    EXPECT_EQ(l.width, static_cast<int>(std::floor(w / t + 1e-9))) << "layer " << k;
    EXPECT_EQ(l.height, static_cast<int>(std::floor(h / t + 1e-9))) << "layer " << k;
    double worst = 0;
    for (int y = 1; y < l.height - 1; ++y)
      for (int x = 1; x < l.width - 1; ++x) {
        const double X0 = (x + 0.5) * t - 0.5, Y0 = (y + 0.5) * t - 0.5;
        worst = std::max(worst, std::abs(l(x, y) - (10 + 0.4 * X0 + 0.3 * Y0)));
      }
    EXPECT_LT(worst, 1.01) << "layer " << k;
  }
  EXPECT_DOUBLE_EQ(OrbExtractor::layerScale(-1), 2.0 / 3.0);
  EXPECT_TRUE(ex.layer(8).empty());
}

// ---- orientation ----------------------------------------------------------------------------

TEST(OrbOrientation, FollowsImageRotation) {
  // Blobs: blurred triangles and ellipses on a flat background, rotated about the image centre.
  const int w = 400, h = 400;
  cv::Mat a(h, w, CV_8U, cv::Scalar(60));
  cv::RNG rng(11);
  for (int i = 0; i < 60; ++i) {
    const cv::Point c(rng.uniform(60, w - 60), rng.uniform(60, h - 60));
    const cv::Scalar grey(rng.uniform(120, 250));
    if (i % 2 == 0) {
      std::vector<cv::Point> tri;
      for (int k = 0; k < 3; ++k)
        tri.emplace_back(c.x + rng.uniform(-25, 25), c.y + rng.uniform(-25, 25));
      cv::fillConvexPoly(a, tri, grey, cv::LINE_AA);
    } else {
      cv::ellipse(a, c, cv::Size(rng.uniform(6, 20), rng.uniform(3, 8)), rng.uniform(0.0, 180.0), 0,
                  300, grey, cv::FILLED, cv::LINE_AA);
    }
  }
  cv::GaussianBlur(a, a, cv::Size(0, 0), 1.0);
  OrbParams p;
  p.max_per_cell = 1000;
  const Features fa = extract(a, p);
  for (double deg : {37.0, -75.0, 150.0}) {
    const cv::Mat M =
        cv::getRotationMatrix2D(cv::Point2f(w / 2.0f - 0.5f, h / 2.0f - 0.5f), deg, 1.0);
    cv::Mat b;
    cv::warpAffine(a, b, M, a.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(60));
    const Features fb = extract(b, p);
    std::vector<double> err;
    std::vector<double> signed_err;
    for (const auto& ka : fa.kp) {
      const cv::Point2d pb = apply(M, ka.x_px, ka.y_px);
      const OrbKeypoint* best = nullptr;
      double best_d = 1.5;
      for (const auto& kb : fb.kp)
        if (kb.layer == ka.layer && std::hypot(kb.x_px - pb.x, kb.y_px - pb.y) < best_d) {
          best_d = std::hypot(kb.x_px - pb.x, kb.y_px - pb.y);
          best = &kb;
        }
      if (!best) continue;
      // Expected: the keypoint's direction vector carried by the linear part of M.
      const double dx = std::cos(ka.angle_rad), dy = std::sin(ka.angle_rad);
      const double ex = M.at<double>(0, 0) * dx + M.at<double>(0, 1) * dy;
      const double ey = M.at<double>(1, 0) * dx + M.at<double>(1, 1) * dy;
      const double e = wrapDeg((best->angle_rad - std::atan2(ey, ex)) * 180 / kPi);
      signed_err.push_back(e);
      err.push_back(std::abs(e));
    }
    ASSERT_GT(err.size(), 30u) << deg;
    std::sort(err.begin(), err.end());
    std::sort(signed_err.begin(), signed_err.end());
    const double bias = signed_err[signed_err.size() / 2];
    auto within = [&](double lim) {
      return static_cast<double>(std::upper_bound(err.begin(), err.end(), lim) - err.begin()) /
             static_cast<double>(err.size());
    };
    std::printf(
        "[orientation] rotation %+.0f deg: %zu repeated keypoints, median error %+.2f deg, "
        "median |error| %.2f deg, %.0f%% within 5 deg, %.0f%% within 15 deg\n",
        deg, err.size(), bias, err[err.size() / 2], 100 * within(5), 100 * within(15));
    EXPECT_LT(std::abs(bias), 1.0) << deg;  // the angle moves by the rotation, no bias
    EXPECT_LT(err[err.size() / 2], 5.0) << deg;
    EXPECT_GT(within(5), 0.6) << deg;
    EXPECT_GT(within(15), 0.9) << deg;
  }
}

TEST(OrbExtractor, KeypointsAreConsistentAndBucketed) {
  const cv::Mat m = texture(480, 320, 9);
  OrbParams p;
  p.grid_cols = 4;
  p.grid_rows = 2;
  p.max_per_cell = 25;
  const Features f = extract(m, p);
  ASSERT_EQ(f.kp.size(), f.desc.size());
  EXPECT_EQ(f.kp.size(), 8u * 25u);  // a textured image fills every cell
  std::vector<int> per_cell(8, 0);
  std::set<int> layers;
  for (std::size_t i = 0; i < f.kp.size(); ++i) {
    const auto& k = f.kp[i];
    EXPECT_GE(k.x_px, 0);
    EXPECT_GE(k.y_px, 0);
    EXPECT_LT(k.x_px, m.cols);
    EXPECT_LT(k.y_px, m.rows);
    EXPECT_GT(k.score, 0);
    EXPECT_EQ(k.octave, k.layer / 2);
    EXPECT_GE(k.scale, OrbExtractor::layerScale(k.layer - 1) - 1e-5);
    EXPECT_LE(k.scale, OrbExtractor::layerScale(k.layer + 1) + 1e-5);
    EXPECT_FLOAT_EQ(k.size_px, static_cast<float>(31 * OrbExtractor::layerScale(k.layer)));
    EXPECT_GT(k.angle_rad, -kPi - 1e-6);
    EXPECT_LE(k.angle_rad, kPi + 1e-6);
    const int cell = std::min(3, static_cast<int>(k.x_px * 4 / m.cols)) +
                     4 * std::min(1, static_cast<int>(k.y_px * 2 / m.rows));
    per_cell[static_cast<std::size_t>(cell)]++;
    if (i > 0 && per_cell[static_cast<std::size_t>(cell)] > 1) {
      EXPECT_LE(k.score, f.kp[i - 1].score) << "strongest first within a cell";
    }
    layers.insert(k.layer);
  }
  for (int n : per_cell) EXPECT_EQ(n, 25);
  EXPECT_GE(layers.size(), 4u) << "keypoints come from several pyramid layers";
  // A flat image has no keypoint.
  cv::Mat flat(320, 480, CV_8U, cv::Scalar(77));
  EXPECT_TRUE(extract(flat, p).kp.empty());
}

TEST(OrbExtractor, DeterministicAndReusable) {
  const cv::Mat m1 = texture(320, 240, 1), m2 = texture(320, 240, 2);
  const ImageU8 i1 = toImage(m1), i2 = toImage(m2);
  OrbExtractor ex(OrbParams{}, 320, 240);
  std::vector<OrbKeypoint> k1, k2, k3;
  std::vector<OrbDescriptor> d1, d2, d3;
  ASSERT_TRUE(ex.process(i1.cview(), k1, d1).isOk());
  ASSERT_TRUE(ex.process(i2.cview(), k2, d2).isOk());
  ASSERT_TRUE(ex.process(i1.cview(), k3, d3).isOk());
  ASSERT_FALSE(k1.empty());
  ASSERT_EQ(k1.size(), k3.size());
  EXPECT_EQ(d1, d3);
  for (std::size_t i = 0; i < k1.size(); ++i) {
    EXPECT_EQ(k1[i].x_px, k3[i].x_px);
    EXPECT_EQ(k1[i].y_px, k3[i].y_px);
    EXPECT_EQ(k1[i].scale, k3[i].scale);
    EXPECT_EQ(k1[i].angle_rad, k3[i].angle_rad);
    EXPECT_EQ(k1[i].score, k3[i].score);
  }
  EXPECT_NE(d1, d2);
  // A second extractor gives the same result.
  OrbExtractor ex2(OrbParams{}, 320, 240);
  ASSERT_TRUE(ex2.process(i1.cview(), k3, d3).isOk());
  EXPECT_EQ(d1, d3);
}

TEST(OrbExtractor, BadParamsAndInputsAreRejected) {
  EXPECT_TRUE(OrbParams{}.validate().isOk());
  auto bad = [](auto mutate) {
    OrbParams p;
    mutate(p);
    return !p.validate().isOk() && !OrbExtractor(p, 200, 200).initStatus().isOk();
  };
  EXPECT_TRUE(bad([](OrbParams& p) { p.num_octaves = 0; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.num_octaves = 5; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.fast_threshold = 0; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.fast_threshold = 255; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.orientation_radius_px = 2; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.orientation_radius_px = 16; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.blur_sigma_px = 0.1; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.blur_sigma_px = std::nan(""); }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.angle_step_deg = 7; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.angle_step_deg = 0; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.grid_cols = 0; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.grid_rows = 0; }));
  EXPECT_TRUE(bad([](OrbParams& p) { p.max_per_cell = 0; }));
  EXPECT_FALSE(OrbExtractor(OrbParams{}, 20, 200).initStatus().isOk());
  EXPECT_FALSE(OrbExtractor(OrbParams{}, 40, 40).initStatus().isOk());  // d_3 below 4 px
  OrbParams one;
  one.num_octaves = 1;
  EXPECT_TRUE(OrbExtractor(one, 40, 40).initStatus().isOk());
  // Wrong image size, empty image.
  OrbExtractor ex(OrbParams{}, 200, 100);
  ASSERT_TRUE(ex.initStatus().isOk());
  std::vector<OrbKeypoint> kp(3);
  std::vector<OrbDescriptor> d(3);
  ImageU8 other(201, 100);
  EXPECT_EQ(ex.process(other.cview(), kp, d).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(kp.empty());
  EXPECT_EQ(ex.process(ImageView<const std::uint8_t>{}, kp, d).code(),
            StatusCode::kInvalidArgument);
}

TEST(OrbExtractor, TimingOnKittiSizedImage) {
  const cv::Mat m = texture(1226, 370, 1226);
  const ImageU8 img = toImage(m);
  OrbExtractor ex(OrbParams{}, m.cols, m.rows);
  std::vector<OrbKeypoint> kp;
  std::vector<OrbDescriptor> d;
  ASSERT_TRUE(ex.process(img.cview(), kp, d).isOk());  // warm-up
  std::vector<FastCorner> level0;
  detectFastCorners(img.cview(), OrbParams{}.fast_threshold, level0);
  // Wall time and this thread's CPU time (the machine may be shared).
  const int runs = 10;
  std::vector<double> wall_ms, cpu_ms;
  for (int i = 0; i < runs; ++i) {
    timespec c0{}, c1{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE(ex.process(img.cview(), kp, d).isOk());
    wall_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
    cpu_ms.push_back((c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) * 1e-6);
  }
  std::sort(wall_ms.begin(), wall_ms.end());
  std::sort(cpu_ms.begin(), cpu_ms.end());
  std::printf(
      "[timing] process() 1226x370, default params: wall median %.2f ms (min %.2f), thread CPU "
      "median %.2f ms (min %.2f); %zu FAST corners on c_0, %zu keypoints out\n",
      wall_ms[runs / 2], wall_ms[0], cpu_ms[runs / 2], cpu_ms[0], level0.size(), kp.size());
  EXPECT_FALSE(kp.empty());
}

}  // namespace
}  // namespace svslam

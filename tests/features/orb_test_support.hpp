#pragma once
// Shared fixtures of the ORB extractor tests: a seeded synthetic texture, conversions, and
// helpers to extract and match features and to map points through a known transform.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <utility>
#include <vector>

#include "core/image.hpp"
#include "features/orb_extractor.hpp"

namespace svslam::orb_test {

inline constexpr double kPi = std::numbers::pi;

// Seeded texture: random filled rectangles, ellipses and triangles of random grey levels and
// sizes (4..80 px, log-uniform) on a smooth gradient, then a light blur and +-3 grey noise.
inline cv::Mat texture(int w, int h, std::uint64_t seed, int shapes = -1) {
  cv::RNG rng(seed);
  cv::Mat img(h, w, CV_8U);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.at<std::uint8_t>(y, x) =
          cv::saturate_cast<std::uint8_t>(90 + 40.0 * x / w + 30.0 * y / h);
  if (shapes < 0) shapes = w * h / 400;
  for (int i = 0; i < shapes; ++i) {
    const double size = std::exp(rng.uniform(std::log(4.0), std::log(80.0)));
    const cv::Point c(rng.uniform(0, w), rng.uniform(0, h));
    const cv::Scalar grey(rng.uniform(0, 256));
    switch (rng.uniform(0, 3)) {
      case 0:
        cv::rectangle(img,
                      cv::Rect(c.x, c.y, static_cast<int>(size),
                               static_cast<int>(size * rng.uniform(0.4, 1.6))),
                      grey, cv::FILLED);
        break;
      case 1:
        cv::ellipse(img, c,
                    cv::Size(static_cast<int>(size / 2) + 1, static_cast<int>(size / 3) + 1),
                    rng.uniform(0.0, 180.0), 0, 360, grey, cv::FILLED, cv::LINE_AA);
        break;
      default: {
        std::vector<cv::Point> tri;
        for (int k = 0; k < 3; ++k)
          tri.emplace_back(c.x + static_cast<int>(rng.uniform(-size, size)),
                           c.y + static_cast<int>(rng.uniform(-size, size)));
        cv::fillConvexPoly(img, tri, grey, cv::LINE_AA);
      }
    }
  }
  cv::GaussianBlur(img, img, cv::Size(0, 0), 0.8);
  cv::Mat noise(h, w, CV_16S);
  rng.fill(noise, cv::RNG::UNIFORM, -3, 4);
  cv::Mat out;
  img.convertTo(img, CV_16S);
  cv::add(img, noise, img);
  img.convertTo(out, CV_8U);
  return out;
}

inline ImageU8 toImage(const cv::Mat& m) {
  ImageU8 img(m.cols, m.rows);
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x) img(x, y) = m.at<std::uint8_t>(y, x);
  return img;
}

struct Features {
  std::vector<OrbKeypoint> kp;
  std::vector<OrbDescriptor> desc;
};

inline Features extract(const cv::Mat& m, const OrbParams& p = {}) {
  OrbExtractor ex(p, m.cols, m.rows);
  EXPECT_TRUE(ex.initStatus().isOk()) << ex.initStatus().message();
  Features f;
  const ImageU8 img = toImage(m);
  const Status s = ex.process(img.cview(), f.kp, f.desc);
  EXPECT_TRUE(s.isOk()) << s.message();
  return f;
}

// Brute-force Hamming nearest neighbour from a to b with Lowe's ratio test.
inline std::vector<std::pair<int, int>> matchRatio(const Features& a, const Features& b,
                                                   double ratio) {
  std::vector<std::pair<int, int>> out;
  for (std::size_t i = 0; i < a.desc.size(); ++i) {
    int best = 1000, second = 1000, best_j = -1;
    for (std::size_t j = 0; j < b.desc.size(); ++j) {
      const int d = hammingDistance(a.desc[i], b.desc[j]);
      if (d < best) {
        second = best;
        best = d;
        best_j = static_cast<int>(j);
      } else if (d < second) {
        second = d;
      }
    }
    if (best_j >= 0 && best < ratio * second) out.emplace_back(static_cast<int>(i), best_j);
  }
  return out;
}

inline cv::Point2d apply(const cv::Mat& m, double x, double y) {
  return {m.at<double>(0, 0) * x + m.at<double>(0, 1) * y + m.at<double>(0, 2),
          m.at<double>(1, 0) * x + m.at<double>(1, 1) * y + m.at<double>(1, 2)};
}

inline double wrapDeg(double a) {
  while (a > 180) a -= 360;
  while (a <= -180) a += 360;
  return a;
}

}  // namespace svslam::orb_test

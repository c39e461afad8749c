// Corner detector on a rendered checkerboard whose corners sit at known sub-pixel positions.
#include "features/corner_detector.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <thread>
#include <vector>

#include "../core/spawning_executor.hpp"

namespace svslam {
namespace {

constexpr double kSquare = 20.0, kOx = 10.3, kOy = 10.6;  // corner grid: kOx + i * kSquare, ...

// Anti-aliased checkerboard (8x8 supersampling), values 40 / 210.
ImageU8 checkerboard(int w, int h) {
  ImageU8 img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double acc = 0;
      for (int sy = 0; sy < 8; ++sy)
        for (int sx = 0; sx < 8; ++sx) {
          const double px = x - 0.5 + (sx + 0.5) / 8, py = y - 0.5 + (sy + 0.5) / 8;
          const int cx = static_cast<int>(std::floor((px - kOx) / kSquare));
          const int cy = static_cast<int>(std::floor((py - kOy) / kSquare));
          acc += ((cx + cy) & 1) ? 210 : 40;
        }
      img(x, y) = static_cast<std::uint8_t>(std::lround(acc / 64));
    }
  return img;
}

void expectCornersAtTruth(CornerResponse resp) {
  const int w = 200, h = 150;
  const ImageU8 img = checkerboard(w, h);
  CornerParams p;
  p.response = resp;
  p.grid_cols = 4;
  p.grid_rows = 3;
  p.border_px = 6;
  CornerDetector det(p, w, h);
  ASSERT_TRUE(det.initStatus().isOk());
  std::vector<Corner> corners;
  ASSERT_TRUE(det.process(img.cview(), corners).isOk());
  int found = 0, truth = 0;
  double worst = 0;
  for (int j = 0; kOy + j * kSquare < h - 8; ++j)
    for (int i = 0; kOx + i * kSquare < w - 8; ++i) {
      const double tx = kOx + i * kSquare, ty = kOy + j * kSquare;
      if (tx < 8 || ty < 8) continue;
      ++truth;
      double best = 1e9;
      for (const auto& c : corners) best = std::min(best, std::hypot(c.x_px - tx, c.y_px - ty));
      if (best < 1.0) {
        ++found;
        worst = std::max(worst, best);
      }
    }
  EXPECT_EQ(found, truth);
  EXPECT_LT(worst, 0.35) << "sub-pixel accuracy";
  // Bucketing: every cell holds at least one corner.
  std::vector<int> per_cell(12, 0);
  for (const auto& c : corners)
    per_cell[static_cast<std::size_t>(std::min(3, static_cast<int>(c.x_px) * 4 / w) +
                                      4 * std::min(2, static_cast<int>(c.y_px) * 3 / h))]++;
  for (int n : per_cell) EXPECT_GT(n, 0);
}

TEST(CornerDetector, PreciseHarrisFindsCheckerboardCorners) {
  expectCornersAtTruth(CornerResponse::kHarris);
}
TEST(CornerDetector, ShiTomasiFindsCheckerboardCorners) {
  expectCornersAtTruth(CornerResponse::kShiTomasi);
}

TEST(CornerDetector, BucketingCapsEachCellAndFlatImagesHaveNoCorners) {
  const ImageU8 img = checkerboard(200, 150);
  CornerParams p;
  p.grid_cols = 2;
  p.grid_rows = 2;
  p.max_per_cell = 3;
  CornerDetector det(p, 200, 150);
  std::vector<Corner> corners;
  ASSERT_TRUE(det.process(img.cview(), corners).isOk());
  EXPECT_EQ(corners.size(), 12u);
  ImageU8 flat(200, 150);
  flat.fill(90);
  ASSERT_TRUE(det.process(flat.cview(), corners).isOk());
  EXPECT_TRUE(corners.empty());
  ImageU8 other(100, 100);
  EXPECT_FALSE(det.process(other.cview(), corners).isOk());
  CornerParams bad;
  bad.harris_k = 1.0;
  EXPECT_FALSE(CornerDetector(bad, 200, 150).initStatus().isOk());
  EXPECT_FALSE(CornerDetector(CornerParams{}, 10, 10).initStatus().isOk());
}

}  // namespace
}  // namespace svslam

namespace svslam {
namespace {

using test_support::SpawningExecutor;

TEST(CornerDetector, RowStripesOnAnyExecutorGiveIdenticalCorners) {
  // A textured image with odd size: random smooth blobs.
  const int w = 203, h = 151;
  ImageU8 img(w, h);
  std::uint32_t s = 12345;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      s = s * 1664525u + 1013904223u;
      const double v = 128 + 60 * std::sin(x * 0.21 + 0.3 * y) * std::cos(y * 0.17 - 0.1 * x) +
                       static_cast<double>(s >> 28);
      img.row(y)[x] = static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
    }
  for (CornerResponse resp : {CornerResponse::kHarris, CornerResponse::kShiTomasi}) {
    CornerParams p;
    p.response = resp;
    CornerDetector serial(p, w, h);
    std::vector<Corner> ref;
    ASSERT_TRUE(serial.process(img.cview(), ref).isOk());
    ASSERT_GT(ref.size(), 20u);
    for (int n : {2, 3, 8}) {
      CornerDetector striped(p, w, h);
      SpawningExecutor ex(n);
      std::vector<Corner> got;
      ASSERT_TRUE(striped.process(img.cview(), got, ex).isOk());
      ASSERT_EQ(got.size(), ref.size()) << n;
      for (std::size_t i = 0; i < ref.size(); ++i) {
        EXPECT_EQ(got[i].x_px, ref[i].x_px);
        EXPECT_EQ(got[i].y_px, ref[i].y_px);
        EXPECT_EQ(got[i].response, ref[i].response);
      }
      EXPECT_EQ(striped.lastMaxResponse(), serial.lastMaxResponse());
    }
  }
}

}  // namespace
}  // namespace svslam

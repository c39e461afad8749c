// Image / ImageView: aligned rows, explicit stride, sub-views, const conversion; camera models
// and time conversions of src/core.
#include "core/image.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "core/camera.hpp"
#include "core/time.hpp"

namespace svslam {
namespace {

TEST(Image, RowsAreAlignedAndStrideCoversWidth) {
  for (int w : {1, 7, 63, 64, 65, 641}) {
    ImageU8 a(w, 3);
    ImageF32 b(w, 3);
    EXPECT_GE(a.stride(), w);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(a.row(1)) % 64, 0u);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(b.row(2)) % 64, 0u);
    EXPECT_EQ(a(0, 0), 0);  // zero-initialised
  }
}

TEST(Image, ViewsShareStorageAndSubViewsKeepTheStride) {
  ImageU8 img(10, 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 10; ++x) img(x, y) = static_cast<std::uint8_t>(10 * y + x);
  ImageView<std::uint8_t> v = img.view();
  ImageView<const std::uint8_t> cv = v;  // mutable view converts to const view
  const auto sub = cv.sub(3, 1, 4, 2);
  EXPECT_EQ(sub.stride, img.stride());
  EXPECT_EQ(sub(0, 0), 13);
  EXPECT_EQ(sub(3, 1), 26);
  v(5, 2) = 99;
  EXPECT_EQ(img(5, 2), 99);
  EXPECT_TRUE(ImageView<const float>().empty());
}

TEST(Image, ResizeKeepsBufferForSameSizeAndMoves) {
  ImageU8 img(32, 8);
  img(1, 1) = 7;
  const std::uint8_t* before = img.row(0);
  img.resize(32, 8);
  EXPECT_EQ(img.row(0), before);
  EXPECT_EQ(img(1, 1), 7);
  ImageU8 moved = std::move(img);
  EXPECT_EQ(moved(1, 1), 7);
  EXPECT_EQ(moved.width(), 32);
}

TEST(Camera, ProjectBackProjectRoundTripAndValidation) {
  StereoCalibration c{700.0, 320.0, 240.0, 0.5, 640, 480};
  ASSERT_TRUE(c.validate().isOk());
  const PinholeCamera cam = c.leftCamera();
  double u, v, x, y;
  ASSERT_TRUE(cam.project(1.0, -0.5, 10.0, u, v));
  cam.backProject(u, v, 10.0, x, y);
  EXPECT_NEAR(x, 1.0, 1e-12);
  EXPECT_NEAR(y, -0.5, 1e-12);
  EXPECT_FALSE(cam.project(0.0, 0.0, -1.0, u, v));
  EXPECT_NEAR(c.depthFromDisparity(c.disparityFromDepth(12.5)), 12.5, 1e-12);
  StereoCalibration bad = c;
  bad.baseline_m = std::nan("");
  EXPECT_FALSE(bad.validate().isOk());
  bad = c;
  bad.f_px = -1;
  EXPECT_FALSE(bad.validate().isOk());
  PinholeCamera badcam = cam;
  badcam.cx_px = INFINITY;
  EXPECT_FALSE(badcam.validate().isOk());
}

TEST(Time, NanosecondConversions) {
  EXPECT_EQ(secondsToNs(1.5), 1500000000);
  EXPECT_EQ(secondsToNs(-0.25), -250000000);
  EXPECT_DOUBLE_EQ(nsToSeconds(2500000000), 2.5);
  EXPECT_EQ(nsToUtime(1234567890), 1234567);
}

}  // namespace
}  // namespace svslam

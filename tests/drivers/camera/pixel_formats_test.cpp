// Camera buffer -> grey conversion: exact GREY / YUYV, MJPEG round trip, truncated buffers.
#include "drivers/camera/pixel_formats.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <vector>

namespace svslam::drivers {
namespace {

ImageU8 pattern(int w, int h) {
  ImageU8 img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img(x, y) = static_cast<std::uint8_t>(128 + 60 * ((x / 8 + y / 8) % 2) - y + x / 3);
  return img;
}

TEST(PixelFormats, GreyWithStride) {
  const int w = 37, h = 11;  // odd sizes
  const ImageU8 ref = pattern(w, h);
  const std::size_t bpl = 48;
  std::vector<std::uint8_t> buf(bpl * h, 0xEE);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) buf[bpl * y + x] = ref(x, y);
  ImageU8 out;
  ASSERT_TRUE(convertToGrey(PixelFormat::kGrey, buf.data(), buf.size(), w, h, bpl, out));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) ASSERT_EQ(out(x, y), ref(x, y)) << x << "," << y;
}

TEST(PixelFormats, YuyvTakesLumaExactly) {
  const int w = 38, h = 9;
  const ImageU8 ref = pattern(w, h);
  std::vector<std::uint8_t> buf(2 * w * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      buf[2 * (w * y + x)] = ref(x, y);
      buf[2 * (w * y + x) + 1] = static_cast<std::uint8_t>(x % 2 ? 17 : 240);
    }
  ImageU8 out;
  ASSERT_TRUE(convertToGrey(PixelFormat::kYuyv, buf.data(), buf.size(), w, h, 0, out));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) ASSERT_EQ(out(x, y), ref(x, y));
  EXPECT_FALSE(convertToGrey(PixelFormat::kYuyv, buf.data(), buf.size(), 37, h, 0, out));
}

TEST(PixelFormats, MjpegRoundTrip) {
  const int w = 64, h = 48;
  const ImageU8 ref = pattern(w, h);
  cv::Mat m(h, w, CV_8U);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) m.at<std::uint8_t>(y, x) = ref(x, y);
  std::vector<std::uint8_t> jpg;
  ASSERT_TRUE(cv::imencode(".jpg", m, jpg, {cv::IMWRITE_JPEG_QUALITY, 98}));
  jpg.resize(jpg.size() + 100, 0);  // UVC zero padding after EOI is fine
  ImageU8 out;
  ASSERT_TRUE(convertToGrey(PixelFormat::kMjpeg, jpg.data(), jpg.size(), w, h, 0, out));
  double sum = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) sum += std::abs(out(x, y) - ref(x, y));
  EXPECT_LT(sum / (w * h), 2.0);
  // The decoded size must be the negotiated one.
  const Status wrong = convertToGrey(PixelFormat::kMjpeg, jpg.data(), jpg.size(), 32, h, 0, out);
  EXPECT_FALSE(wrong);
  EXPECT_NE(wrong.message().find("64x48"), std::string::npos) << wrong.message();
}

TEST(PixelFormats, CorruptMjpegIsAnError) {
  const int w = 64, h = 48;
  cv::Mat m(h, w, CV_8U, cv::Scalar(90));
  std::vector<std::uint8_t> jpg;
  ASSERT_TRUE(cv::imencode(".jpg", m, jpg));
  ImageU8 out;
  const Status truncated =
      convertToGrey(PixelFormat::kMjpeg, jpg.data(), jpg.size() / 2, w, h, 0, out);
  EXPECT_EQ(truncated.code(), StatusCode::kCorruptData);
  EXPECT_NE(truncated.message().find("truncated"), std::string::npos) << truncated.message();
  std::vector<std::uint8_t> garbage(500, 0x5A);
  garbage[0] = 0xFF, garbage[1] = 0xD8, garbage[498] = 0xFF, garbage[499] = 0xD9;
  EXPECT_EQ(convertToGrey(PixelFormat::kMjpeg, garbage.data(), garbage.size(), w, h, 0, out).code(),
            StatusCode::kCorruptData);
  EXPECT_FALSE(convertToGrey(PixelFormat::kMjpeg, garbage.data(), 1, w, h, 0, out));
}

TEST(PixelFormats, TruncatedBuffersAreErrors) {
  std::vector<std::uint8_t> buf(100 * 10);
  ImageU8 out;
  const Status g = convertToGrey(PixelFormat::kGrey, buf.data(), 999, 100, 10, 0, out);
  EXPECT_EQ(g.code(), StatusCode::kCorruptData);
  EXPECT_NE(g.message().find("GREY buffer truncated"), std::string::npos) << g.message();
  const Status y = convertToGrey(PixelFormat::kYuyv, buf.data(), buf.size(), 100, 10, 0, out);
  EXPECT_NE(y.message().find("YUYV buffer truncated"), std::string::npos) << y.message();
  // Stride shorter than a row is a parameter error.
  EXPECT_EQ(convertToGrey(PixelFormat::kGrey, buf.data(), buf.size(), 100, 10, 50, out).code(),
            StatusCode::kInvalidArgument);
  EXPECT_FALSE(convertToGrey(PixelFormat::kGrey, nullptr, 0, 100, 10, 0, out));
}

TEST(PixelFormats, SplitSideBySide) {
  const ImageU8 full = pattern(40, 7);
  ImageU8 l, r;
  ASSERT_TRUE(splitSideBySide(full, l, r));
  ASSERT_EQ(l.width(), 20);
  ASSERT_EQ(r.height(), 7);
  for (int y = 0; y < 7; ++y)
    for (int x = 0; x < 20; ++x) {
      ASSERT_EQ(l(x, y), full(x, y));
      ASSERT_EQ(r(x, y), full(x + 20, y));
    }
  EXPECT_FALSE(splitSideBySide(pattern(41, 7), l, r));
}

TEST(PixelFormats, NamesAndFourcc) {
  EXPECT_EQ(parsePixelFormat("YUYV").value(), PixelFormat::kYuyv);
  EXPECT_EQ(parsePixelFormat("MJPG").value(), PixelFormat::kMjpeg);
  EXPECT_FALSE(parsePixelFormat("RGB3"));
  EXPECT_EQ(fourccToString(pixelFormatFourcc(PixelFormat::kMjpeg)), "MJPG");
  EXPECT_EQ(pixelFormatFromFourcc(pixelFormatFourcc(PixelFormat::kGrey)).value(),
            PixelFormat::kGrey);
}

}  // namespace
}  // namespace svslam::drivers

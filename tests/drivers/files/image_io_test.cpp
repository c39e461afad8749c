#include "drivers/files/image_io.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "../../core/test_files.hpp"

namespace svslam::drivers {
namespace {

namespace fs = std::filesystem;
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

class ImageIoTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = svslam::test::freshTestDir("svslam_image_io_test_"); }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void writeBytes(const std::string& p, const std::vector<unsigned char>& b) const {
    std::ofstream f(p, std::ios::binary);
    f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  }
  void writeText(const std::string& p, const std::string& s) const {
    writeBytes(p, std::vector<unsigned char>(s.begin(), s.end()));
  }
  std::vector<unsigned char> readBytes(const std::string& p) const {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
  }
  // Number of "*.tmp" files left in the test folder (recursively).
  int tmpFiles() const {
    int n = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir_))
      if (e.path().extension() == ".tmp") ++n;
    return n;
  }
  static cv::Mat noiseImage(int w, int h, int type) {
    cv::Mat m(h, w, type);
    cv::randu(m, cv::Scalar::all(0), cv::Scalar::all(255));
    return m;
  }

  fs::path dir_;
};

ImageF32 sampleDisparity() {
  ImageF32 img(5, 3);
  const float values[15] = {0.0f, 1.5f,  -2.25f, 1e-20f, 3e20f,  //
                            kInf, 64.0f, 7.125f, -kInf,  12.0f,  //
                            kNan, 0.5f,  255.0f, 99.75f, 1.0f};
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) img(x, y) = values[y * 5 + x];
  return img;
}

void expectSameBits(const ImageF32& a, const ImageF32& b) {
  ASSERT_EQ(a.width(), b.width());
  ASSERT_EQ(a.height(), b.height());
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) {
      if (std::isnan(a(x, y))) {
        EXPECT_TRUE(std::isnan(b(x, y))) << x << "," << y;
      } else {
        EXPECT_EQ(a(x, y), b(x, y)) << x << "," << y;
      }
    }
}

// ---- PFM ----

TEST_F(ImageIoTest, PfmRoundTripIsExactAndStoresBottomRowFirst) {
  const ImageF32 img = sampleDisparity();
  ASSERT_TRUE(writePfm(path("d.pfm"), ImageF32(2, 2).cview()).isOk());  // replaced below
  ASSERT_TRUE(writePfm(path("d.pfm"), img.cview()).isOk());
  EXPECT_EQ(tmpFiles(), 0);
  const std::vector<unsigned char> bytes = readBytes(path("d.pfm"));
  const std::string header = "Pf\n5 3\n-1.0\n";
  ASSERT_EQ(bytes.size(), header.size() + 15 * 4);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + header.size()), header);
  float first = 0;  // little-endian on the test hosts: the bottom row's first pixel (NaN)
  std::memcpy(&first, bytes.data() + header.size(), 4);
  EXPECT_TRUE(std::isnan(first));

  const Result<ImageF32> back = readPfm(path("d.pfm"));
  ASSERT_TRUE(back.isOk()) << back.status().message();
  expectSameBits(img, back.value());
}

TEST_F(ImageIoTest, PfmBigEndianAndCrlfHeader) {
  // 2x2, positive scale = big-endian; file rows bottom to top: (3, 4) then (1, 2).
  std::vector<unsigned char> b;
  const std::string header = "Pf\r\n2 2\r\n1.0\r\n";
  b.insert(b.end(), header.begin(), header.end());
  for (float v : {3.0f, 4.0f, 1.0f, 2.0f}) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<unsigned char>(u >> s));
  }
  writeBytes(path("be.pfm"), b);
  const Result<ImageF32> r = readPfm(path("be.pfm"));
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r.value()(0, 0), 1.0f);
  EXPECT_EQ(r.value()(1, 0), 2.0f);
  EXPECT_EQ(r.value()(0, 1), 3.0f);
  EXPECT_EQ(r.value()(1, 1), 4.0f);
}

TEST_F(ImageIoTest, PfmBadHeadersAreCorruptDataWithReason) {
  const std::string px(2 * 2 * 4, '\0');
  const std::map<std::string, std::string> cases = {
      {"P5\n2 2\n-1.0\n" + px, "Pf"},
      {"Pf\nabc 2\n-1.0\n" + px, "width"},
      {"Pf\n2 -2\n-1.0\n" + px, "height"},
      {"Pf\n2 2\n0.0\n" + px, "scale"},
      {"Pf\n2 2\nxyz\n" + px, "scale"},
      {"Pf\n2 2", "scale"},
      {"Pf\n2", "height"},
      {"Pf\n2 2\n-1.0\n" + px.substr(0, 9), "truncated"},
      {"Pf\n2 2\n-1.0\n" + px + "extra", "bytes"},
      {"Pf\n100000 100000\n-1.0\n", "larger"},
      {"\x89PNG garbage", "Pf"},
  };
  int i = 0;
  for (const auto& [content, reason] : cases) {
    const std::string p = path("bad" + std::to_string(i++) + ".pfm");
    writeText(p, content);
    const Result<ImageF32> r = readPfm(p);
    ASSERT_FALSE(r.isOk()) << content;
    EXPECT_EQ(r.status().code(), StatusCode::kCorruptData) << r.status().message();
    EXPECT_NE(r.status().message().find(reason), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find(p), std::string::npos) << r.status().message();
  }
  writeText(path("colour.pfm"), "PF\n1 1\n-1.0\n" + std::string(12, '\0'));
  EXPECT_EQ(readPfm(path("colour.pfm")).status().code(), StatusCode::kInvalidArgument);
}

TEST_F(ImageIoTest, LoadDisparityPfmMapsNonFiniteToInf) {
  const ImageF32 img = sampleDisparity();
  ASSERT_TRUE(writePfm(path("d.pfm"), img.cview()).isOk());
  const Result<ImageF32> r = loadDisparity(path("d.pfm"), 1.0);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r.value()(0, 2), kInf);  // was NaN
  EXPECT_EQ(r.value()(3, 1), kInf);  // was -inf
  EXPECT_EQ(r.value()(0, 1), kInf);
  EXPECT_EQ(r.value()(2, 0), -2.25f);  // finite values exactly as stored
  EXPECT_EQ(r.value()(3, 2), 99.75f);
}

// ---- disparity PNG ----

TEST_F(ImageIoTest, DisparityPng16RoundTripKittiConvention) {
  const ImageF32 img = sampleDisparity();
  ASSERT_TRUE(writeDisparityPng16(path("d.png"), img.cview()).isOk());
  EXPECT_EQ(tmpFiles(), 0);
  const cv::Mat raw = cv::imread(path("d.png"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16UC1);
  EXPECT_EQ(raw.at<std::uint16_t>(0, 0), 0);      // 0 -> invalid
  EXPECT_EQ(raw.at<std::uint16_t>(0, 1), 384);    // 1.5 * 256
  EXPECT_EQ(raw.at<std::uint16_t>(0, 2), 0);      // negative
  EXPECT_EQ(raw.at<std::uint16_t>(0, 3), 0);      // rounds to 0
  EXPECT_EQ(raw.at<std::uint16_t>(0, 4), 65535);  // saturated
  EXPECT_EQ(raw.at<std::uint16_t>(1, 0), 0);      // inf
  EXPECT_EQ(raw.at<std::uint16_t>(1, 2), 1824);   // 7.125 * 256
  EXPECT_EQ(raw.at<std::uint16_t>(2, 0), 0);      // NaN

  const Result<ImageF32> r = loadDisparity(path("d.png"), 256.0);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) {
      const float d = img(x, y);
      const float back = r.value()(x, y);
      if (!std::isfinite(d) || d <= 1.0f / 512 || d > 65535.0f / 256) {
        EXPECT_TRUE(back == kInf || (d > 255 && back == 65535.0f / 256)) << x << "," << y;
      } else {
        EXPECT_NEAR(back, d, 1.0 / 512) << x << "," << y;
      }
    }
}

TEST_F(ImageIoTest, LoadDisparity8BitPngDividesByScale) {
  const cv::Mat m = (cv::Mat_<std::uint8_t>(2, 3) << 0, 16, 255, 1, 8, 100);
  ASSERT_TRUE(cv::imwrite(path("g.png"), m));
  const Result<ImageF32> r = loadDisparity(path("g.png"), 4.0);
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r.value().width(), 3);
  EXPECT_EQ(r.value().height(), 2);
  EXPECT_EQ(r.value()(0, 0), kInf);
  EXPECT_FLOAT_EQ(r.value()(1, 0), 4.0f);
  EXPECT_FLOAT_EQ(r.value()(2, 0), 63.75f);
  EXPECT_FLOAT_EQ(r.value()(0, 1), 0.25f);
  EXPECT_FLOAT_EQ(r.value()(2, 1), 25.0f);
}

TEST_F(ImageIoTest, LoadDisparityBadArguments) {
  ASSERT_TRUE(cv::imwrite(path("g.png"), cv::Mat(2, 2, CV_8UC1, cv::Scalar(3))));
  for (double s : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    EXPECT_EQ(loadDisparity(path("g.png"), s).status().code(), StatusCode::kInvalidArgument) << s;
  }
  writeText(path("d.txt"), "1 2 3");
  EXPECT_EQ(loadDisparity(path("d.txt"), 1.0).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(loadDisparity(path("nope.png"), 1.0).status().code(), StatusCode::kNotFound);
  EXPECT_EQ(loadDisparity(path("nope.pfm"), 1.0).status().code(), StatusCode::kNotFound);
  ASSERT_TRUE(cv::imwrite(path("rgb.png"), noiseImage(4, 4, CV_8UC3)));
  EXPECT_EQ(loadDisparity(path("rgb.png"), 1.0).status().code(), StatusCode::kInvalidArgument);
}

// ---- grey images: bad inputs never crash ----

TEST_F(ImageIoTest, LoadGreyMissingGarbageEmptyAndDirectory) {
  const Result<ImageU8> missing = loadGrey(path("missing.png"));
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_NE(missing.status().message().find("does not exist: " + path("missing.png")),
            std::string::npos)
      << missing.status().message();
  std::vector<unsigned char> garbage(4096);
  for (std::size_t i = 0; i < garbage.size(); ++i)
    garbage[i] = static_cast<unsigned char>(i * 131 + 7);
  for (const char* name : {"garbage.png", "garbage.jpg", "garbage.bin"}) {
    writeBytes(path(name), garbage);
    const Result<ImageU8> r = loadGrey(path(name));
    ASSERT_FALSE(r.isOk()) << name;
    EXPECT_EQ(r.status().code(), StatusCode::kCorruptData) << r.status().message();
    EXPECT_NE(r.status().message().find("cannot decode image " + path(name)), std::string::npos);
  }
  writeBytes(path("empty.png"), {});
  EXPECT_EQ(loadGrey(path("empty.png")).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(loadGrey(dir_.string()).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(loadMask(path("garbage.png")).status().code(), StatusCode::kCorruptData);
}

TEST_F(ImageIoTest, TruncatedPngAndJpegAreCorruptDataAtEveryLength) {
  const cv::Mat src = noiseImage(64, 48, CV_8UC3);
  for (const char* ext : {".png", ".jpg"}) {
    std::vector<unsigned char> full;
    ASSERT_TRUE(cv::imencode(ext, src, full));
    writeBytes(path(std::string("full") + ext), full);
    const Result<ImageU8> ok = loadGrey(path(std::string("full") + ext));
    ASSERT_TRUE(ok.isOk()) << ok.status().message();
    EXPECT_EQ(ok.value().width(), 64);
    EXPECT_EQ(ok.value().height(), 48);
    // Cut the file at many lengths, including just before the last byte.
    std::vector<std::size_t> cuts;
    for (std::size_t n = 1; n < full.size(); n += 1 + full.size() / 97) cuts.push_back(n);
    cuts.push_back(full.size() - 1);
    for (std::size_t n : cuts) {
      const std::string p = path("cut" + std::to_string(n) + ext);
      writeBytes(p, std::vector<unsigned char>(full.begin(), full.begin() + n));
      const Result<ImageU8> r = loadGrey(p);
      ASSERT_FALSE(r.isOk()) << ext << " cut at " << n << " of " << full.size();
      EXPECT_EQ(r.status().code(), StatusCode::kCorruptData) << r.status().message();
      EXPECT_NE(r.status().message().find(p), std::string::npos) << r.status().message();
    }
  }
}

TEST_F(ImageIoTest, LoadGreyConvertsColourAndRefuses16Bit) {
  const cv::Mat bgr = noiseImage(7, 5, CV_8UC3);
  ASSERT_TRUE(cv::imwrite(path("c.png"), bgr));
  cv::Mat expected;
  cv::cvtColor(bgr, expected, cv::COLOR_BGR2GRAY);
  const Result<ImageU8> r = loadGrey(path("c.png"));
  ASSERT_TRUE(r.isOk()) << r.status().message();
  ASSERT_EQ(r.value().width(), 7);
  ASSERT_EQ(r.value().height(), 5);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 7; ++x) EXPECT_EQ(r.value()(x, y), expected.at<std::uint8_t>(y, x));

  const cv::Mat grey = noiseImage(9, 4, CV_8UC1);
  ASSERT_TRUE(cv::imwrite(path("g.pgm"), grey));
  const Result<ImageU8> g = loadGrey(path("g.pgm"));
  ASSERT_TRUE(g.isOk()) << g.status().message();
  EXPECT_EQ(g.value()(8, 3), grey.at<std::uint8_t>(3, 8));

  ASSERT_TRUE(cv::imwrite(path("w.png"), cv::Mat(3, 3, CV_16UC1, cv::Scalar(1000))));
  const Result<ImageU8> w = loadGrey(path("w.png"));
  ASSERT_FALSE(w.isOk());
  EXPECT_EQ(w.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(w.status().message().find("16-bit"), std::string::npos) << w.status().message();
}

TEST_F(ImageIoTest, LoadMaskKeepsOnlyWhite) {
  const cv::Mat m = (cv::Mat_<std::uint8_t>(1, 4) << 0, 128, 255, 1);
  ASSERT_TRUE(cv::imwrite(path("m.png"), m));
  const Result<ImageU8> r = loadMask(path("m.png"));
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r.value()(0, 0), 0);
  EXPECT_EQ(r.value()(1, 0), 0);
  EXPECT_EQ(r.value()(2, 0), 255);
  EXPECT_EQ(r.value()(3, 0), 0);
}

// ---- real palette PNGs (Middlebury v2) ----

TEST_F(ImageIoTest, PalettePngReadThroughPalette) {
  const std::string dir = std::string(SVSLAM_DATA_DIR) + "/middlebury_v2/tsukuba";
  if (!fs::exists(dir + "/groundtruth.png")) GTEST_SKIP() << "no Middlebury data at " << dir;
  // groundtruth.png is a 4-bit palette image; disc.png 8-bit grey with 0/128/255.
  const Result<ImageU8> gt = loadGrey(dir + "/groundtruth.png");
  ASSERT_TRUE(gt.isOk()) << gt.status().message();
  ASSERT_EQ(gt.value().width(), 384);
  ASSERT_EQ(gt.value().height(), 288);
  std::map<int, int> hist;
  for (int y = 0; y < 288; ++y)
    for (int x = 0; x < 384; ++x) ++hist[gt.value()(x, y)];
  const std::map<int, int> expected = {{0, 22896},   {80, 50668}, {96, 6595},  {112, 1150},
                                       {128, 13174}, {160, 5555}, {176, 4830}, {224, 5724}};
  EXPECT_EQ(hist, expected);

  const Result<ImageF32> d = loadDisparity(dir + "/groundtruth.png", 16.0);
  ASSERT_TRUE(d.isOk()) << d.status().message();
  int unknown = 0;
  float max_d = 0;
  for (int y = 0; y < 288; ++y)
    for (int x = 0; x < 384; ++x) {
      if (d.value()(x, y) == kInf)
        ++unknown;
      else
        max_d = std::max(max_d, d.value()(x, y));
    }
  EXPECT_EQ(unknown, 22896);
  EXPECT_EQ(max_d, 14.0f);

  const Result<ImageU8> nonocc = loadMask(dir + "/nonocc.png");  // 1-bit palette
  const Result<ImageU8> disc = loadMask(dir + "/disc.png");
  ASSERT_TRUE(nonocc.isOk() && disc.isOk());
  int n_nonocc = 0;
  int n_disc = 0;
  for (int y = 0; y < 288; ++y)
    for (int x = 0; x < 384; ++x) {
      n_nonocc += nonocc.value()(x, y) == 255;
      n_disc += disc.value()(x, y) == 255;
    }
  EXPECT_EQ(n_nonocc, 85438);
  EXPECT_EQ(n_disc, 15790);
}

// ---- writers ----

TEST_F(ImageIoTest, WritersRefuseUnknownExtensionAndEmptyImage) {
  const ImageF32 img = sampleDisparity();
  EXPECT_EQ(writePfm(path("d.png"), img.cview()).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(writeDisparityPng16(path("d.pfm"), img.cview()).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(writeColorPng(path("d.jpg"), img.cview(), 64.0f).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(writePfm(path("e.pfm"), ImageView<const float>()).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(writeColorPng(path("d.png"), img.cview(), 0.0f).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(writeColorPng(path("d.png"), img.cview(), kNan).code(), StatusCode::kInvalidArgument);
  EXPECT_FALSE(fs::exists(path("d.png")));
}

TEST_F(ImageIoTest, FailedWritesAreIoErrorsAndLeaveNoTmp) {
  const ImageF32 img = sampleDisparity();
  // Missing directory.
  const std::string missing = path("no_such_dir/d.pfm");
  Status s = writePfm(missing, img.cview());
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find(missing), std::string::npos) << s.message();
  // A regular file where a directory should be (fails for root too).
  writeText(path("file"), "x");
  s = writeDisparityPng16(path("file/d.png"), img.cview());
  EXPECT_EQ(s.code(), StatusCode::kIoError) << s.message();
  // The target is a non-empty directory: the temporary is written, the rename fails.
  fs::create_directories(path("busy.png/inner"));
  s = writeColorPng(path("busy.png"), img.cview(), 64.0f);
  EXPECT_EQ(s.code(), StatusCode::kIoError) << s.message();
  EXPECT_NE(s.message().find(path("busy.png")), std::string::npos) << s.message();
  EXPECT_EQ(tmpFiles(), 0);
}

TEST_F(ImageIoTest, UnwritableDirectoryIsIoError) {
  if (::geteuid() == 0) GTEST_SKIP() << "running as root: directory permissions do not apply";
  fs::create_directories(path("ro"));
  fs::permissions(path("ro"), fs::perms::owner_read | fs::perms::owner_exec);
  const Status s = writePfm(path("ro/d.pfm"), sampleDisparity().cview());
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find(path("ro/d.pfm")), std::string::npos) << s.message();
  fs::permissions(path("ro"), fs::perms::owner_all);
  EXPECT_EQ(tmpFiles(), 0);
}

TEST_F(ImageIoTest, ColorPngNearIsWarmInvalidIsBlack) {
  ImageF32 d(4, 1);
  d(0, 0) = 0.0f;    // far
  d(1, 0) = 64.0f;   // near (= max_disp)
  d(2, 0) = kInf;    // invalid
  d(3, 0) = 500.0f;  // beyond max: clamped to the warm end
  ASSERT_TRUE(writeColorPng(path("c.png"), d.cview(), 64.0f).isOk());
  const cv::Mat c = cv::imread(path("c.png"), cv::IMREAD_COLOR);
  ASSERT_EQ(c.cols, 4);
  const cv::Vec3b far = c.at<cv::Vec3b>(0, 0);
  const cv::Vec3b near = c.at<cv::Vec3b>(0, 1);
  EXPECT_GT(far[0], far[2]);    // blue > red
  EXPECT_GT(near[2], near[0]);  // red > blue
  EXPECT_EQ(c.at<cv::Vec3b>(0, 2), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(c.at<cv::Vec3b>(0, 3), near);
}

}  // namespace
}  // namespace svslam::drivers

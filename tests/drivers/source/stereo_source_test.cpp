// Stereo sources on the real sequences of ../shared/data: KITTI calibration and timing, EuRoC
// rectification (matched features land on the same row), and clear errors for bad folders.
#include "drivers/source/stereo_source.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "drivers/files/opencv_view.hpp"

namespace fs = std::filesystem;

namespace svslam::drivers {
namespace {

std::string data(const std::string& sub) { return std::string(SVSLAM_DATA_DIR) + "/" + sub; }

// Median |y_left - y_right| of ORB matches that pass a ratio test.
double medianRowError(const ImageU8& l, const ImageU8& r) {
  auto orb = cv::ORB::create(1500);
  std::vector<cv::KeyPoint> kl, kr;
  cv::Mat dl, dr;
  orb->detectAndCompute(asMat(l), cv::noArray(), kl, dl);
  orb->detectAndCompute(asMat(r), cv::noArray(), kr, dr);
  cv::BFMatcher bf(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  bf.knnMatch(dl, dr, knn, 2);
  std::vector<double> dy;
  for (const auto& m : knn)
    if (m.size() == 2 && m[0].distance < 0.7 * m[1].distance)
      dy.push_back(std::abs(kl[static_cast<std::size_t>(m[0].queryIdx)].pt.y -
                            kr[static_cast<std::size_t>(m[0].trainIdx)].pt.y));
  if (dy.size() < 20) return INFINITY;
  std::nth_element(dy.begin(), dy.begin() + static_cast<std::ptrdiff_t>(dy.size() / 2), dy.end());
  return dy[dy.size() / 2];
}

TEST(StereoSource, KittiSequenceVariantLayout) {
  if (!fs::exists(data("kitti_odometry_seq_a")))
    GTEST_SKIP() << "shared data absent: " << data("kitti_odometry_seq_a");
  auto src = openStereoSource("kitti:" + data("kitti_odometry_seq_a"));
  ASSERT_TRUE(src.isOk()) << src.status().message();
  const auto& c = (*src)->calibration();
  EXPECT_EQ((*src)->size(), 51);
  EXPECT_NEAR(c.f_px, 707.0912, 1e-3);
  EXPECT_NEAR(c.baseline_m, 0.537, 0.001);
  EXPECT_EQ(c.width, 1226);
  EXPECT_EQ(c.height, 370);
  StereoFrame f;
  int n = 0;
  TimeNs last = -1;
  for (;;) {
    auto more = (*src)->next(f);
    ASSERT_TRUE(more.isOk()) << more.status().message();
    if (!*more) break;
    EXPECT_EQ(f.index, n);
    EXPECT_GT(f.t_ns, last);
    last = f.t_ns;
    ++n;
  }
  EXPECT_EQ(n, 51);
  EXPECT_EQ(last, 50 * 100 * kNsPerMs);  // 10 Hz without times.txt
}

TEST(StereoSource, EurocIsRectified) {
  if (!fs::exists(data("euroc_mh01_first320")))
    GTEST_SKIP() << "shared data absent: " << data("euroc_mh01_first320");
  auto src = openStereoSource("euroc:" + data("euroc_mh01_first320"));
  ASSERT_TRUE(src.isOk()) << src.status().message();
  const auto& c = (*src)->calibration();
  EXPECT_EQ((*src)->size(), 320);
  EXPECT_NEAR(c.baseline_m, 0.110, 0.003);
  StereoFrame f;
  ASSERT_TRUE((*src)->next(f).isOk());
  EXPECT_EQ(f.t_ns, 1403636584763555584);
  EXPECT_EQ(f.left.width(), 752);
  const double dy = medianRowError(f.left, f.right);
  std::printf("EuRoC frame 0: median |dy| of matched features after rectification %.3f px\n", dy);
  EXPECT_LT(dy, 0.5);
  // The same measure on the raw (distorted, unrectified) pair, to show the test can tell.
  const std::string raw0 = data("euroc_mh01_first320/mav0/cam0/data/1403636584763555584.png");
  const std::string raw1 = data("euroc_mh01_first320/mav0/cam1/data/1403636584763555584.png");
  cv::Mat r0 = cv::imread(raw0, cv::IMREAD_GRAYSCALE), r1 = cv::imread(raw1, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(r0.empty() || r1.empty());
  ImageU8 a(r0.cols, r0.rows), b(r1.cols, r1.rows);
  r0.copyTo(asMat(a));
  r1.copyTo(asMat(b));
  const double dy_raw = medianRowError(a, b);
  std::printf("EuRoC frame 0: median |dy| on the raw pair %.3f px\n", dy_raw);
  EXPECT_GT(dy_raw, dy + 1.0);
}

TEST(StereoSource, BadFoldersGiveClearErrors) {
  EXPECT_EQ(openStereoSource("kitti:/nonexistent/seq").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(openStereoSource("euroc:/nonexistent/seq").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(openStereoSource("video:/x").status().code(), StatusCode::kInvalidArgument);
  const fs::path dir = fs::temp_directory_path() / "svslam_bad_kitti";
  fs::remove_all(dir);
  fs::create_directories(dir / "image_0");
  fs::create_directories(dir / "image_1");
  std::ofstream(dir / "image_0" / "000000.png") << "not a png";
  std::ofstream(dir / "image_1" / "000000.png") << "not a png";
  std::ofstream(dir / "calib.txt") << "P0: 1 2 3\n";
  auto s = openKittiSource(dir.string());
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.status().message().find("calib.txt"), std::string::npos) << s.status().message();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace svslam::drivers

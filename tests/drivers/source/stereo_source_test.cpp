// Stereo sources on the real sequences of ../shared/data: KITTI calibration and timing, EuRoC
// rectification (matched features land on the same row), and clear errors for bad folders; on
// small generated KITTI folders: pairing by name, calib.txt and times.txt errors.
#include "drivers/source/stereo_source.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

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

// Writes DIR/mav0/camN/sensor.yaml for a distortion-free 640x480 camera with extrinsic T_BS.
void writeEurocSensor(const fs::path& dir, int n, const Eigen::Isometry3d& T_BS) {
  const fs::path cam = dir / "mav0" / ("cam" + std::to_string(n));
  fs::create_directories(cam);
  std::ofstream f(cam / "sensor.yaml");
  f.precision(17);
  f << "T_BS:\n  data: [";
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) f << (r || c ? ", " : "") << T_BS.matrix()(r, c);
  f << "]\nresolution: [640, 480]\nintrinsics: [400, 400, 320, 240]\n"
       "distortion_coefficients: [0, 0, 0, 0]\n";
}

// The rectified left camera in the body frame: cam0 itself for a rig already rectified; for a
// baseline tilted in the image plane, cam0 turned about its optical centre so that its x axis
// lies along the baseline (cv::stereoRectify's rectified frame).
TEST(StereoSource, EurocRectifiedLeftCameraInTheBodyFrame) {
  const fs::path dir = fs::temp_directory_path() / ("svslam_euroc_rect_" + std::to_string(getpid()));
  fs::remove_all(dir);
  Eigen::Isometry3d T_BS0 = Eigen::Isometry3d::Identity();
  T_BS0.linear() = Eigen::AngleAxisd(1.2, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).matrix();
  T_BS0.translation() = Eigen::Vector3d(-0.02, -0.06, 0.01);
  writeEurocSensor(dir, 0, T_BS0);
  writeEurocSensor(dir, 1, T_BS0 * Eigen::Translation3d(0.11, 0, 0));
  auto T = eurocBodyToRectifiedLeft(dir.string());
  ASSERT_TRUE(T) << T.status().message();
  EXPECT_LT((T->matrix() - T_BS0.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  const Eigen::Vector3d baseline(0.11, 0.011, 0);  // cam1's centre in cam0, 5.7 deg off x
  writeEurocSensor(dir, 1, T_BS0 * Eigen::Translation3d(baseline));
  T = eurocBodyToRectifiedLeft(dir.string());
  ASSERT_TRUE(T) << T.status().message();
  EXPECT_LT((T->translation() - T_BS0.translation()).norm(), 1e-12);
  const Eigen::Vector3d x_rect = T->linear().col(0), b_body = T_BS0.linear() * baseline.normalized();
  EXPECT_LT(x_rect.cross(b_body).norm(), 1e-9) << x_rect.transpose() << " / " << b_body.transpose();
  fs::remove_all(dir / "mav0" / "cam1");
  EXPECT_EQ(eurocBodyToRectifiedLeft(dir.string()).status().code(), StatusCode::kNotFound);
  fs::remove_all(dir);
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

// A small KITTI folder in a fresh temporary directory: 32x24 images filled with 20 * i (left)
// and 20 * i + 1 (right) for the frame names given, calib.txt and optional times.txt.
class KittiFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("svslam_kitti_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "image_l");
    fs::create_directories(dir_ / "image_r");
    calib(kCalibP0, kCalibP1);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static constexpr const char* kCalibP0 = "P0: 700 0 300 0 0 700 180 0 0 0 1 0";
  static constexpr const char* kCalibP1 = "P1: 700 0 300 -350 0 700 180 0 0 0 1 0";
  void image(const std::string& side, int i, const std::string& name = "") {
    const cv::Mat m(24, 32, CV_8U, cv::Scalar(20 * i + (side == "image_r" ? 1 : 0)));
    char buf[16];
    std::snprintf(buf, sizeof buf, "%06d.png", i);
    ASSERT_TRUE(cv::imwrite((dir_ / side / (name.empty() ? buf : name)).string(), m));
  }
  void calib(const std::string& p0, const std::string& p1) {
    std::ofstream(dir_ / "calib.txt") << p0 << "\n" << p1 << "\n";
  }
  std::string openError() {
    auto s = openKittiSource(dir_.string());
    return s.isOk() ? "(opened)" : s.status().message();
  }
  fs::path dir_;
};

TEST_F(KittiFolder, PairsImagesByNameAndSkipsFramesWithOneSideMissing) {
  for (int i : {0, 1, 2, 4, 5}) image("image_l", i);  // left 000003 missing
  for (int i : {0, 1, 2, 3, 5}) image("image_r", i);  // right 000004 missing
  image("image_l", 9, ".hidden.png");                 // not an image of the sequence
  image("image_r", 9, ".000003.png");
  std::ofstream(dir_ / "times.txt") << "0.0\n0.1\n0.2\n0.3\n0.4\n0.5\n";
  auto src = openKittiSource(dir_.string());
  ASSERT_TRUE(src.isOk()) << src.status().message();
  EXPECT_EQ((*src)->size(), 4);
  EXPECT_EQ((*src)->skippedFrames(), 2);
  const std::string detail = (*src)->skippedFramesDetail();
  EXPECT_NE(detail.find("000003"), std::string::npos) << detail;
  EXPECT_NE(detail.find("000004"), std::string::npos) << detail;
  const int expected[] = {0, 1, 2, 5};
  StereoFrame f;
  for (int k = 0; k < 4; ++k) {
    auto more = (*src)->next(f);
    ASSERT_TRUE(more.isOk() && *more) << k;
    EXPECT_EQ(f.index, k);
    EXPECT_EQ(f.left(0, 0), 20 * expected[k]) << "frame " << k;
    EXPECT_EQ(f.right(0, 0), 20 * expected[k] + 1) << "frame " << k << ": left and right differ";
    EXPECT_EQ(f.t_ns, expected[k] * 100 * kNsPerMs);  // the stamp of its own name
  }
  auto end = (*src)->next(f);
  ASSERT_TRUE(end.isOk());
  EXPECT_FALSE(*end);
}

TEST_F(KittiFolder, CalibrationErrorsSayWhatIsWrong) {
  image("image_l", 0);
  image("image_r", 0);
  ASSERT_EQ(openError(), "(opened)");
  calib("P0: 700 0 300 0 0 700 nan 0 0 0 1 0", kCalibP1);
  EXPECT_NE(openError().find("'nan' is not finite"), std::string::npos) << openError();
  calib("P0: 700 0 300 0 0 700 180 0 0 0 1 0", "P1: 700 0 inf -350 0 700 180 0 0 0 1 0");
  EXPECT_NE(openError().find("'inf' is not finite"), std::string::npos) << openError();
  calib("P0: 700 0 300 0 0 700 1e400 0 0 0 1 0", kCalibP1);
  EXPECT_NE(openError().find("'1e400' is not finite"), std::string::npos) << openError();
  calib("P0: 0 0 300 0 0 700 180 0 0 0 1 0", "P1: 0 0 300 -350 0 700 180 0 0 0 1 0");
  EXPECT_NE(openError().find("fx (its 1st number) must be positive"), std::string::npos)
      << openError();
  calib("P0: 1e308 0 300 0 0 1e308 180 0 0 0 1 0", "P1: 1e308 0 300 -1e308 0 1e308 180 0 0 0 1 0");
  EXPECT_NE(openError().find("f_px = 1e+308 is out of range"), std::string::npos) << openError();
  calib(kCalibP0, "P1: 700 0 310 -350 0 700 180 0 0 0 1 0");
  EXPECT_NE(openError().find("P1 cx = 310 differs from P0's 300"), std::string::npos)
      << openError();
  calib(kCalibP0, "P1: 700 0 300 -350");
  EXPECT_NE(openError().find("needs 12 numbers, got 4"), std::string::npos) << openError();
}

TEST_F(KittiFolder, TimeStampsMustFitAndIncrease) {
  for (int i = 0; i < 3; ++i) {
    image("image_l", i);
    image("image_r", i);
  }
  std::ofstream(dir_ / "times.txt") << "0.0\n0.1\n1e20\n";
  EXPECT_NE(openError().find("times.txt:3: time stamp"), std::string::npos) << openError();
  EXPECT_NE(openError().find("out of range"), std::string::npos) << openError();
  std::ofstream(dir_ / "times.txt") << "0.0\n0.2\n0.1\n";
  EXPECT_NE(openError().find("times.txt:3"), std::string::npos) << openError();
  EXPECT_NE(openError().find("not after the previous one"), std::string::npos) << openError();
  std::ofstream(dir_ / "times.txt") << "0.0\n0.1\nabc\n";
  EXPECT_NE(openError().find("times.txt:3: 'abc' is not a number"), std::string::npos)
      << openError();
  std::ofstream(dir_ / "times.txt") << "0.0\n0.1\n0.2\n";
  EXPECT_EQ(openError(), "(opened)");
}

TEST(StereoSource, UnknownSourceListsEveryKind) {
  auto s = openStereoSource("video:/x");
  ASSERT_FALSE(s.isOk());
  for (const char* kind : {"kitti:", "euroc:", "synthetic", "v4l2:", "libcamera:", "lcm:"})
    EXPECT_NE(s.status().message().find(kind), std::string::npos)
        << kind << ": " << s.status().message();
}

}  // namespace
}  // namespace svslam::drivers

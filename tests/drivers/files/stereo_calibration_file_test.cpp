// Stereo calibration file: written by writeStereoCalibrationFile, read back identically by the
// reader of the v4l2:/libcamera: sources; a calibration of the rendered chessboard scene is
// accepted by the v4l2: source on the fake driver and rectifies its rows.
#include "drivers/files/stereo_calibration_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../../core/test_files.hpp"
#include "../calib/chessboard_scene.hpp"
#include "../camera/fake_v4l2_device.hpp"
#include "drivers/calib/calibration_pairs.hpp"
#include "drivers/calib/stereo_calibrator.hpp"
#include "drivers/camera/v4l2_source.hpp"

namespace fs = std::filesystem;

namespace svslam::drivers {
namespace {

StereoCalibrationFile sample() {
  StereoCalibrationFile c;
  c.K1 = (cv::Mat_<double>(3, 3) << 533.95855064903787, 0, 342.19372842374815, 0,
          533.88392284994359, 234.87709200578874, 0, 0, 1);
  c.K2 = (cv::Mat_<double>(3, 3) << 537.5, 0, 327.9, 0, 537.1, 249.7, 0, 0, 1);
  c.D1 = (cv::Mat_<double>(1, 5) << -0.2833095244867465, 0.051457488252069396, 1.2e-3, -1.0e-4,
          0.0939);
  c.D2 = (cv::Mat_<double>(1, 5) << -0.29, 0.138, -6e-4, 5.4e-4, -0.0565);
  const cv::Mat rvec = (cv::Mat_<double>(3, 1) << 0.01, -0.004, 0.002);
  cv::Rodrigues(rvec, c.R);
  c.T = (cv::Mat_<double>(3, 1) << -0.0832296, 0.000938036, -0.000140066);
  c.width = 640;
  c.height = 480;
  return c;
}

void expectSame(const cv::Mat& a, const cv::Mat& b, const char* what) {
  ASSERT_EQ(a.total(), b.total()) << what;
  EXPECT_EQ(cv::norm(a.reshape(1, 1), b.reshape(1, 1), cv::NORM_INF), 0.0) << what;
}

TEST(StereoCalibrationFile, RoundTripIsExactInEveryFormat) {
  const fs::path dir = test::freshTestDir("svslam_calib_file_");
  const StereoCalibrationFile c = sample();
  for (const char* name : {"stereo.yaml", "stereo.xml", "stereo.json"}) {
    const std::string file = (dir / name).string();
    ASSERT_TRUE(writeStereoCalibrationFile(file, c).isOk()) << name;
    EXPECT_FALSE(fs::exists(dir / (std::string(".tmp-") + name))) << name;
    auto back = readStereoCalibrationFile(file);
    ASSERT_TRUE(back.isOk()) << back.status().message();
    expectSame(back->K1, c.K1, "K1");
    expectSame(back->K2, c.K2, "K2");
    expectSame(back->D1, c.D1, "D1");
    expectSame(back->D2, c.D2, "D2");
    expectSame(back->R, c.R, "R");
    expectSame(back->T, c.T, "T");
    EXPECT_EQ(back->width, 640);
    EXPECT_EQ(back->height, 480);
  }
  Status bad = writeStereoCalibrationFile((dir / "no/such/dir/stereo.yaml").string(), c);
  EXPECT_FALSE(bad.isOk());
  EXPECT_NE(bad.message().find("cannot write calibration file"), std::string::npos);
}

TEST(StereoCalibrationFile, CalibratedSceneIsAcceptedByTheV4l2SourceAndRectifies) {
  const test::ChessboardScene s;
  StereoCalibrationParams p;
  p.square_m = s.square_m;
  StereoCalibrator cal(p);
  std::vector<cv::Mat> left, right;
  for (int i = 0; i < 9; ++i) {
    left.emplace_back();
    right.emplace_back();
    ASSERT_TRUE(s.render(i, 0, left.back()) && s.render(i, 1, right.back()));
    bool accepted = false;
    ASSERT_TRUE(cal.addPair(left.back(), right.back(), std::to_string(i), accepted).isOk());
  }
  auto res = cal.calibrate();
  ASSERT_TRUE(res.isOk()) << res.status().message();
  const fs::path dir = test::freshTestDir("svslam_calib_file_");
  const std::string file = (dir / "stereo.yaml").string();
  ASSERT_TRUE(writeStereoCalibrationFile(file, res->file).isOk());

  // The fake cameras show pose 4 (board in the middle); frame content is base + sequence.
  testing::FakeV4l2Device dev;
  for (int cam = 0; cam < 2; ++cam) {
    testing::FakeCameraConfig c;
    c.base.resize(s.width, s.height);
    const cv::Mat& src = cam == 0 ? left[4] : right[4];
    for (int y = 0; y < s.height; ++y)
      for (int x = 0; x < s.width; ++x) c.base(x, y) = src.at<std::uint8_t>(y, x);
    c.script = {testing::FakeEvent::frame(1'000'000, 0)};
    dev.addCamera(cam == 0 ? "/dev/video0" : "/dev/video1", std::move(c));
  }
  auto src = openV4l2Source("/dev/video0,/dev/video1?width=640&height=480&calib=" + file, dev);
  ASSERT_TRUE(src.isOk()) << src.status().message();
  const StereoCalibration& rc = (*src)->calibration();
  EXPECT_NEAR(rc.baseline_m, s.baseline_m, 0.01 * s.baseline_m);
  EXPECT_NEAR(rc.f_px, res->P1.at<double>(0, 0), 1e-9);
  StereoFrame frame;
  auto more = (*src)->next(frame);
  ASSERT_TRUE(more.isOk() && *more) << more.status().message();
  // The board corners of the rectified views lie on the same rows.
  const cv::Mat l(frame.left.height(), frame.left.width(), CV_8U, frame.left.row(0),
                  static_cast<std::size_t>(frame.left.stride()));
  const cv::Mat r(frame.right.height(), frame.right.width(), CV_8U, frame.right.row(0),
                  static_cast<std::size_t>(frame.right.stride()));
  std::vector<cv::Point2f> cl, cr;
  ASSERT_TRUE(cv::findChessboardCorners(l, cv::Size(s.cols, s.rows), cl));
  ASSERT_TRUE(cv::findChessboardCorners(r, cv::Size(s.cols, s.rows), cr));
  cv::cornerSubPix(l, cl, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 50, 1e-3));
  cv::cornerSubPix(r, cr, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 50, 1e-3));
  double worst = 0.0;
  for (std::size_t i = 0; i < cl.size(); ++i)
    worst = std::max(worst, static_cast<double>(std::abs(cl[i].y - cr[i].y)));
  EXPECT_LT(worst, 0.5);
}

// The real pairs (shared/data/chessboard_calib): calibrated, the file written, then the same 13
// pairs played by the fake V4L2 cameras through the v4l2: source with that file: the board
// corners found again in the rectified frames lie on the same rows.
TEST(StereoCalibrationFile, RealPairsCalibratedThenRectifiedByTheV4l2Source) {
  const std::string data = std::string(SVSLAM_DATA_DIR) + "/chessboard_calib";
  if (!fs::exists(data)) GTEST_SKIP() << "no calibration data at " << data;
  auto pairs = listCalibrationPairs(data);
  ASSERT_TRUE(pairs.isOk()) << pairs.status().message();
  StereoCalibrator cal(StereoCalibrationParams{});  // 9x6, 25 mm
  std::vector<cv::Mat> left, right;
  for (const auto& p : *pairs) {
    left.push_back(cv::imread(p.left, cv::IMREAD_GRAYSCALE));
    right.push_back(cv::imread(p.right, cv::IMREAD_GRAYSCALE));
    bool accepted = false;
    ASSERT_TRUE(cal.addPair(left.back(), right.back(), p.name, accepted).isOk());
  }
  auto res = cal.calibrate();
  ASSERT_TRUE(res.isOk()) << res.status().message();
  const fs::path dir = test::freshTestDir("svslam_calib_file_");
  const std::string file = (dir / "stereo.yaml").string();
  ASSERT_TRUE(writeStereoCalibrationFile(file, res->file).isOk());

  // Frame k shows pair k: the fake driver adds the sequence number to every pixel (mod 256),
  // so each base holds the image minus k (mod 256) and the frame is the image exactly.
  const int n = static_cast<int>(left.size());
  testing::FakeV4l2Device dev;
  for (int cam = 0; cam < 2; ++cam) {
    testing::FakeCameraConfig c;
    for (int k = 0; k < n; ++k) {
      const cv::Mat& img = cam == 0 ? left[static_cast<std::size_t>(k)]
                                    : right[static_cast<std::size_t>(k)];
      ImageU8 b(img.cols, img.rows);
      for (int y = 0; y < img.rows; ++y)
        for (int x = 0; x < img.cols; ++x)
          b(x, y) = static_cast<std::uint8_t>(img.at<std::uint8_t>(y, x) - k);
      c.bases.push_back(std::move(b));
      c.script.push_back(testing::FakeEvent::frame(1'000'000 + k * 100'000'000LL,
                                                   static_cast<std::uint32_t>(k)));
    }
    dev.addCamera(cam == 0 ? "/dev/video0" : "/dev/video1", std::move(c));
  }
  auto src = openV4l2Source("/dev/video0,/dev/video1?width=640&height=480&calib=" + file, dev);
  ASSERT_TRUE(src.isOk()) << src.status().message();
  double sum = 0.0, worst = 0.0;
  int corners = 0, frames = 0;
  for (int k = 0; k < n; ++k) {
    StereoFrame frame;
    auto more = (*src)->next(frame);
    ASSERT_TRUE(more.isOk() && *more) << "frame " << k << ": " << more.status().message();
    ++frames;
    const cv::Mat l(frame.left.height(), frame.left.width(), CV_8U, frame.left.row(0),
                    static_cast<std::size_t>(frame.left.stride()));
    const cv::Mat r(frame.right.height(), frame.right.width(), CV_8U, frame.right.row(0),
                    static_cast<std::size_t>(frame.right.stride()));
    std::vector<cv::Point2f> cl, cr;
    if (!cv::findChessboardCorners(l, cv::Size(9, 6), cl) ||
        !cv::findChessboardCorners(r, cv::Size(9, 6), cr))
      continue;  // a board cut by the rectified image border
    const cv::TermCriteria stop(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 50, 1e-3);
    cv::cornerSubPix(l, cl, cv::Size(5, 5), cv::Size(-1, -1), stop);
    cv::cornerSubPix(r, cr, cv::Size(5, 5), cv::Size(-1, -1), stop);
    for (std::size_t i = 0; i < cl.size(); ++i) {
      const double dy = std::abs(static_cast<double>(cl[i].y - cr[i].y));
      sum += dy;
      worst = std::max(worst, dy);
      ++corners;
    }
  }
  EXPECT_EQ(frames, n);
  ASSERT_GE(corners, 10 * 54) << "boards found again in fewer than 10 rectified pairs";
  const double mean = sum / corners;
  std::printf("rectified by the v4l2: source: %d corners, |dy| mean %.3f px, max %.3f px\n",
              corners, mean, worst);
  EXPECT_LE(mean, 0.3);
  EXPECT_LE(worst, 1.5);
}

}  // namespace
}  // namespace svslam::drivers

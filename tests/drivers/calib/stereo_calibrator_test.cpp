// StereoCalibrator: the rendered chessboard scene (known cameras) recovered; real pairs
// (OpenCV's left01..right14 sample) meet the RMS / epipolar bounds; rejections and input errors.
#include "drivers/calib/stereo_calibrator.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "chessboard_scene.hpp"
#include "drivers/calib/calibration_pairs.hpp"

namespace svslam::drivers {
namespace {

using svslam::test::ChessboardScene;

StereoCalibrationParams sceneParams(const ChessboardScene& s) {
  StereoCalibrationParams p;
  p.board_cols = s.cols;
  p.board_rows = s.rows;
  p.square_m = s.square_m;
  return p;
}

void addScene(const ChessboardScene& s, int n, StereoCalibrator& cal) {
  for (int i = 0; i < n; ++i) {
    cv::Mat l, r;
    ASSERT_TRUE(s.render(i, 0, l) && s.render(i, 1, r)) << "pose " << i << " leaves the view";
    bool accepted = false;
    ASSERT_TRUE(cal.addPair(l, r, std::string("pose").append(std::to_string(i)), accepted).isOk());
    EXPECT_TRUE(accepted) << "pose " << i;
  }
}

TEST(StereoCalibrator, RecoversRenderedCameras) {
  const ChessboardScene s;
  StereoCalibrator cal(sceneParams(s));
  addScene(s, 12, cal);
  auto r = cal.calibrate();
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_TRUE(r->rejected.empty());
  EXPECT_LT(r->rms_pair_px, 0.2);
  for (const cv::Mat* K : {&r->file.K1, &r->file.K2}) {
    EXPECT_NEAR(K->at<double>(0, 0), s.fx, 0.005 * s.fx);
    EXPECT_NEAR(K->at<double>(1, 1), s.fy, 0.005 * s.fy);
    EXPECT_NEAR(K->at<double>(0, 2), s.cx, 2.0);
    EXPECT_NEAR(K->at<double>(1, 2), s.cy, 2.0);
  }
  EXPECT_NEAR(r->file.T.at<double>(0), -s.baseline_m, 0.005 * s.baseline_m);
  EXPECT_NEAR(r->baseline_m, s.baseline_m, 0.005 * s.baseline_m);
  EXPECT_LT(r->epipolar_mean_px, 0.1);
  EXPECT_EQ(r->file.width, s.width);
  EXPECT_EQ(r->file.height, s.height);
  cv::Mat l, rr;
  s.render(0, 0, l);
  s.render(0, 1, rr);
  const cv::Mat check = renderRectifiedCheck(*r, l, rr);
  EXPECT_EQ(check.cols, 2 * s.width);
  EXPECT_EQ(check.rows, s.height);
  EXPECT_EQ(check.type(), CV_8UC3);
}

TEST(StereoCalibrator, RejectsBlurredAndDuplicatePairsAndMissingBoards) {
  const ChessboardScene s;
  StereoCalibrator cal(sceneParams(s));
  addScene(s, 7, cal);
  cv::Mat l, r, blurred, empty(s.height, s.width, CV_8U, cv::Scalar(s.background));
  s.render(1, 0, l);
  s.render(1, 1, r);
  bool accepted = true;
  ASSERT_TRUE(cal.addPair(l, r, "again", accepted).isOk());
  EXPECT_FALSE(accepted);
  s.render(8, 0, l);
  s.render(8, 1, r);
  cv::GaussianBlur(r, blurred, cv::Size(0, 0), 4.0);
  ASSERT_TRUE(cal.addPair(l, blurred, "soft", accepted).isOk());
  EXPECT_FALSE(accepted);
  ASSERT_TRUE(cal.addPair(empty, r, "noboard", accepted).isOk());
  EXPECT_FALSE(accepted);
  ASSERT_EQ(cal.rejections().size(), 3u);
  EXPECT_EQ(cal.rejections()[0].reason.rfind("duplicate of pose1", 0), 0u)
      << cal.rejections()[0].reason;
  EXPECT_EQ(cal.rejections()[1].reason.rfind("blurred (right sharpness", 0), 0u)
      << cal.rejections()[1].reason;
  EXPECT_EQ(cal.rejections()[2].reason, "board not found in left");
  auto res = cal.calibrate();
  ASSERT_TRUE(res.isOk()) << res.status().message();
  EXPECT_EQ(res->used.size(), 7u);
  EXPECT_EQ(res->rejected.size(), 3u);
}

TEST(StereoCalibrator, InputErrorsNameTheProblem) {
  const ChessboardScene s;
  StereoCalibrationParams p = sceneParams(s);
  p.board_cols = 2;
  EXPECT_FALSE(StereoCalibrator(p).initStatus().isOk());
  StereoCalibrator cal(sceneParams(s));
  EXPECT_NE(cal.calibrate().status().message().find("no image pair"), std::string::npos);
  cv::Mat l, r;
  s.render(0, 0, l);
  s.render(0, 1, r);
  bool accepted = false;
  cv::Mat small;
  cv::resize(r, small, cv::Size(320, 240));
  Status mixed = cal.addPair(l, small, "p0", accepted);
  EXPECT_NE(mixed.message().find("mixed image sizes"), std::string::npos) << mixed.message();
  ASSERT_TRUE(cal.addPair(l, r, "p1", accepted).isOk());
  mixed = cal.addPair(small, small, "p2", accepted);
  EXPECT_NE(mixed.message().find("mixed image sizes: p2 is 320x240, the first pair is 640x480"),
            std::string::npos)
      << mixed.message();
  auto few = cal.calibrate();
  EXPECT_NE(few.status().message().find("too few usable pairs: 1 of 1, need 6"), std::string::npos)
      << few.status().message();

  StereoCalibrationParams wrong = sceneParams(s);
  wrong.board_cols = 10;
  wrong.board_rows = 7;
  StereoCalibrator none(wrong);
  ASSERT_TRUE(none.addPair(l, r, "p1", accepted).isOk());
  EXPECT_NE(
      none.calibrate().status().message().find("10x7 board (inner corners) was found in none"),
      std::string::npos);
}

TEST(StereoCalibrator, PoorCoverageIsAnError) {
  ChessboardScene s;
  StereoCalibrator cal(sceneParams(s));
  // Poses 0, 3, 6, 9, ... keep the board in the left third of the view.
  for (int i = 0; i < 8; ++i) {
    cv::Mat l, r;
    ASSERT_TRUE(s.render(3 * (i % 3), 0, l) && s.render(3 * (i % 3), 1, r));
    cv::Mat lt, rt;  // small shifts so that the views are not duplicates
    const cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, 3 * i, 0, 1, 0);
    cv::warpAffine(l, lt, M, l.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    cv::warpAffine(r, rt, M, r.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    bool accepted = false;
    ASSERT_TRUE(cal.addPair(lt, rt, std::string("p").append(std::to_string(i)), accepted).isOk());
  }
  auto res = cal.calibrate();
  ASSERT_FALSE(res.isOk());
  EXPECT_NE(res.status().message().find("poor coverage"), std::string::npos)
      << res.status().message();
}

TEST(StereoCalibrator, RealPairsMeetTheBounds) {
  const std::string dir = std::string(SVSLAM_DATA_DIR) + "/chessboard_calib";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "no calibration data at " << dir;
  auto pairs = listCalibrationPairs(dir);
  ASSERT_TRUE(pairs.isOk()) << pairs.status().message();
  ASSERT_EQ(pairs->size(), 13u);
  StereoCalibrator cal(StereoCalibrationParams{});  // 9x6, 25 mm
  for (const auto& p : *pairs) {
    const cv::Mat l = cv::imread(p.left, cv::IMREAD_GRAYSCALE);
    const cv::Mat r = cv::imread(p.right, cv::IMREAD_GRAYSCALE);
    bool accepted = false;
    ASSERT_TRUE(cal.addPair(l, r, p.name, accepted).isOk());
  }
  auto res = cal.calibrate();
  ASSERT_TRUE(res.isOk()) << res.status().message();
  EXPECT_LE(res->rms_pair_px, 0.5);
  EXPECT_LE(res->rms_left_px, 0.5);
  EXPECT_LE(res->rms_right_px, 0.5);
  EXPECT_LE(res->epipolar_mean_px, 0.3);
  EXPECT_GE(res->used.size(), 12u);
  EXPECT_NEAR(res->baseline_m, 0.083, 0.003);  // 25 mm squares: the rig's ~8.3 cm baseline
  EXPECT_EQ(res->file.width, 640);
  EXPECT_EQ(res->file.height, 480);
}

}  // namespace
}  // namespace svslam::drivers

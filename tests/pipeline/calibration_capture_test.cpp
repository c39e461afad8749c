// Live calibration on the fake V4L2 driver: the cameras show the rendered chessboard scene (a
// new board pose every frame), --grab-every N offers every N-th pair until K are accepted, and
// the pairs calibrate to the rendered cameras.
#include "pipeline/tools/calibration_capture.hpp"

#include <gtest/gtest.h>

#include "../drivers/calib/chessboard_scene.hpp"
#include "../drivers/camera/fake_v4l2_device.hpp"

namespace svslam::cli {
namespace {

using drivers::testing::FakeCameraConfig;
using drivers::testing::FakeEvent;
using drivers::testing::FakeV4l2Device;

ImageU8 toImage(const cv::Mat& m) {
  ImageU8 out(m.cols, m.rows);
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x) out(x, y) = m.at<std::uint8_t>(y, x);
  return out;
}

// Two cameras whose frame `seq` shows pose seq % 10 of the scene, `frames` frames each.
void addCameras(FakeV4l2Device& dev, const test::ChessboardScene& s, int frames) {
  for (int cam = 0; cam < 2; ++cam) {
    FakeCameraConfig c;
    for (int i = 0; i < 10; ++i) {
      cv::Mat view;
      ASSERT_TRUE(s.render(i, cam, view));
      c.bases.push_back(toImage(view));
    }
    for (int f = 0; f < frames; ++f)
      c.script.push_back(
          FakeEvent::frame(1'000'000 + f * 33'000'000LL, static_cast<std::uint32_t>(f)));
    dev.addCamera(cam == 0 ? "/dev/video0" : "/dev/video1", std::move(c));
  }
}

TEST(CalibrationCapture, GrabEveryNthPairUntilKAcceptedThenCalibrates) {
  const test::ChessboardScene s;
  FakeV4l2Device dev;
  addCameras(dev, s, 40);
  auto cam =
      drivers::openRawStereoCapture("v4l2:/dev/video0,/dev/video1?width=640&height=480", dev);
  ASSERT_TRUE(cam.isOk()) << cam.status().message();
  drivers::StereoCalibrationParams p;
  p.square_m = s.square_m;
  drivers::StereoCalibrator cal(p);
  LiveCollectOptions o;
  o.grab_every = 3;  // frames 3, 6, ... = sequences 2, 5, 8, 11, ... = poses 2, 5, 8, 1, 4, ...
  o.pairs = 8;
  cv::Mat check_l, check_r;
  LiveCollectStats stats;
  std::vector<std::string> lines;
  ASSERT_TRUE(collectLivePairs(
                  **cam, cal, o, {}, [&](const std::string& l) { lines.push_back(l); }, check_l,
                  check_r, stats)
                  .isOk());
  EXPECT_EQ(cal.acceptedPairs(), 8);
  EXPECT_EQ(stats.frames_read, 24);
  EXPECT_EQ(stats.offered, 8);
  ASSERT_EQ(lines.size(), 8u);
  EXPECT_EQ(lines[0], "pair 1 (frame3): accepted, 1/8");
  EXPECT_EQ(check_l.size(), cv::Size(640, 480));
  auto res = cal.calibrate();
  ASSERT_TRUE(res.isOk()) << res.status().message();
  // The frames are the rendered views plus the sequence number (a uniform grey shift).
  EXPECT_NEAR(res->file.K1.at<double>(0, 0), s.fx, 0.01 * s.fx);
  EXPECT_NEAR(res->baseline_m, s.baseline_m, 0.01 * s.baseline_m);
}

TEST(CalibrationCapture, TriggerGrabsTheNextPairAndStops) {
  const test::ChessboardScene s;
  FakeV4l2Device dev;
  addCameras(dev, s, 10);
  auto cam =
      drivers::openRawStereoCapture("v4l2:/dev/video0,/dev/video1?width=640&height=480", dev);
  ASSERT_TRUE(cam.isOk()) << cam.status().message();
  drivers::StereoCalibrator cal(drivers::StereoCalibrationParams{});
  int calls = 0;
  auto trigger = [&calls]() {
    ++calls;
    return calls == 2 ? Trigger::kGrab : calls == 5 ? Trigger::kStop : Trigger::kNone;
  };
  cv::Mat check_l, check_r;
  LiveCollectStats stats;
  ASSERT_TRUE(
      collectLivePairs(**cam, cal, LiveCollectOptions{}, trigger, {}, check_l, check_r, stats)
          .isOk());
  EXPECT_EQ(stats.frames_read, 4);
  EXPECT_EQ(stats.offered, 1);
}

TEST(CalibrationCapture, RawCaptureNeedsNoCalibrationButAKnownScheme) {
  FakeV4l2Device dev;
  auto kitti = drivers::openRawStereoCapture("kitti:/data", dev);
  ASSERT_FALSE(kitti.isOk());
  EXPECT_NE(kitti.status().message().find("needs a v4l2: or libcamera: source"), std::string::npos);
  auto missing = drivers::openRawStereoCapture("v4l2:/dev/video5,/dev/video6", dev);
  EXPECT_FALSE(missing.isOk());
}

}  // namespace
}  // namespace svslam::cli

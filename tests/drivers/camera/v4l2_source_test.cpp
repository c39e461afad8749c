// v4l2: stereo source on the fake driver: timestamp pairing with skew, side-by-side split,
// rectification from a calibration file written here, spec and calibration errors.
#include "drivers/camera/v4l2_source.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>

#include "fake_v4l2_device.hpp"

namespace fs = std::filesystem;

namespace svslam::drivers {
namespace {

using testing::FakeCameraConfig;
using testing::FakeEvent;
using testing::FakeV4l2Device;

constexpr int kW = 80, kH = 60;
constexpr double kF = 70.0, kB = 0.12;  // px, m

// Identity-rectified pair: equal pinhole cameras, no distortion, principal point at the image
// centre (where stereoRectify puts it), right camera kB metres along +x.
std::string writeCalib(const std::string& name, int w, int h, double d1_0 = 0.0,
                       bool drop_t = false) {
  const fs::path path = fs::temp_directory_path() / ("svslam_v4l2_" + name + ".yaml");
  cv::FileStorage f(path.string(), cv::FileStorage::WRITE);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << kF, 0, (w - 1) / 2.0, 0, kF, (h - 1) / 2.0, 0, 0, 1);
  f << "K1" << K << "D1" << (cv::Mat_<double>(1, 5) << d1_0, 0, 0, 0, 0);
  f << "K2" << K << "D2" << cv::Mat::zeros(1, 5, CV_64F);
  f << "R" << cv::Mat::eye(3, 3, CV_64F);
  if (!drop_t) f << "T" << (cv::Mat_<double>(3, 1) << -kB, 0, 0);
  f << "image_width" << w << "image_height" << h;
  return path.string();
}

FakeCameraConfig camera(int w, int seed, std::deque<FakeEvent> script) {
  FakeCameraConfig c;
  c.base = testing::testPattern(w, kH, seed);
  c.script = std::move(script);
  return c;
}

int maxInteriorDiff(const ImageU8& a, const ImageU8& b) {
  int m = 0;
  for (int y = 2; y < a.height() - 2; ++y)
    for (int x = 2; x < a.width() - 2; ++x) m = std::max(m, std::abs(a(x, y) - b(x, y)));
  return m;
}

TEST(V4l2Source, PairsTwoCamerasByTimestampAndRectifiesIdentity) {
  FakeV4l2Device dev;
  const TimeNs ms = kNsPerMs;
  // Right camera starts one frame early (seq 100 has no partner) and has 2 ms jitter.
  dev.addCamera("/dev/video0",
                camera(kW, 0,
                       {FakeEvent::frame(1000 * ms, 0), FakeEvent::frame(1033 * ms, 1),
                        FakeEvent::frame(1066 * ms, 2)}));
  dev.addCamera("/dev/video1",
                camera(kW, 1,
                       {FakeEvent::frame(967 * ms, 100), FakeEvent::frame(1002 * ms, 101),
                        FakeEvent::frame(1031 * ms, 102), FakeEvent::frame(1066 * ms, 103)}));
  const std::string calib = writeCalib("identity", kW, kH);
  auto src = openV4l2Source("/dev/video0,/dev/video1?width=80&height=60&calib=" + calib, dev);
  ASSERT_TRUE(src) << src.status().message();
  const StereoCalibration& c = (*src)->calibration();
  EXPECT_NEAR(c.f_px, kF, 1e-6);
  EXPECT_NEAR(c.cx_px, (kW - 1) / 2.0, 1e-6);
  EXPECT_NEAR(c.cy_px, (kH - 1) / 2.0, 1e-6);
  EXPECT_NEAR(c.baseline_m, kB, 1e-9);
  EXPECT_EQ((*src)->size(), -1);
  StereoFrame f;
  for (std::uint32_t i = 0; i < 3; ++i) {
    auto r = (*src)->next(f);
    ASSERT_TRUE(r) << r.status().message();
    ASSERT_TRUE(*r);
    EXPECT_EQ(f.index, static_cast<int>(i));
    EXPECT_EQ(f.t_ns, (1000 + 33 * static_cast<TimeNs>(i)) * ms);
    // Identity rectification: images equal up to interpolation; left seq i, right seq 101 + i.
    EXPECT_LE(maxInteriorDiff(f.left, testing::expectedFrame(dev.camera("/dev/video0").base, i)),
              1);
    EXPECT_LE(
        maxInteriorDiff(f.right, testing::expectedFrame(dev.camera("/dev/video1").base, 101 + i)),
        1);
  }
  auto* v4l2 = dynamic_cast<V4l2StereoSource*>(src->get());
  ASSERT_NE(v4l2, nullptr);
  EXPECT_EQ(v4l2->unpairedDrops(0), 0u);
  EXPECT_EQ(v4l2->unpairedDrops(1), 1u);
  EXPECT_EQ(dev.starved(), 0);
}

TEST(V4l2Source, SideBySideSplitsOneDevice) {
  FakeV4l2Device dev;
  dev.addCamera("/dev/video2", camera(2 * kW, 3, {FakeEvent::frame(5 * kNsPerMs, 7)}));
  const std::string calib = writeCalib("sbs", kW, kH);
  auto src = openV4l2Source(
      "/dev/video2?layout=side-by-side&width=160&height=60&format=YUYV&fps=15&calib=" + calib, dev);
  ASSERT_TRUE(src) << src.status().message();
  StereoFrame f;
  auto r = (*src)->next(f);
  ASSERT_TRUE(r) << r.status().message();
  const ImageU8 full = testing::expectedFrame(dev.camera("/dev/video2").base, 7);
  ImageU8 want_l, want_r;
  ASSERT_TRUE(splitSideBySide(full, want_l, want_r));
  EXPECT_EQ(f.left.width(), kW);
  EXPECT_LE(maxInteriorDiff(f.left, want_l), 1);
  EXPECT_LE(maxInteriorDiff(f.right, want_r), 1);
  EXPECT_EQ(f.t_ns, 5 * kNsPerMs);
  // The script ended: a timeout error naming the device.
  auto end = (*src)->next(f);
  ASSERT_FALSE(end);
  EXPECT_NE(end.status().message().find("/dev/video2"), std::string::npos);
}

TEST(V4l2Source, CalibrationErrorsNameKeyAndFile) {
  FakeV4l2Device dev;
  dev.addCamera("/dev/video0", camera(kW, 0, {}));
  dev.addCamera("/dev/video1", camera(kW, 1, {}));
  const std::string devs = "/dev/video0,/dev/video1?width=80&height=60&calib=";
  const std::string nan = writeCalib("nan", kW, kH, std::nan(""));
  auto r1 = openV4l2Source(devs + nan, dev);
  ASSERT_FALSE(r1);
  EXPECT_NE(r1.status().message().find("'D1' contains NaN"), std::string::npos)
      << r1.status().message();
  EXPECT_NE(r1.status().message().find(nan), std::string::npos);
  auto r2 = openV4l2Source(devs + writeCalib("no_t", kW, kH, 0.0, true), dev);
  ASSERT_FALSE(r2);
  EXPECT_NE(r2.status().message().find("missing calibration key 'T'"), std::string::npos);
  auto r3 = openV4l2Source(devs + writeCalib("size", 640, 480), dev);
  ASSERT_FALSE(r3);
  EXPECT_NE(r3.status().message().find("calibrated for 640x480 but the capture is 80x60"),
            std::string::npos)
      << r3.status().message();
  auto r4 = openV4l2Source(devs + "/nonexistent/calib.yaml", dev);
  EXPECT_EQ(r4.status().code(), StatusCode::kNotFound);
  EXPECT_EQ(dev.openFds(), 0);  // calibration is checked before any camera is opened
}

TEST(V4l2Source, SpecErrors) {
  FakeV4l2Device dev;
  const std::string calib = writeCalib("spec", kW, kH);
  auto unknown = openV4l2Source("/dev/video0,/dev/video1?exposure=5&calib=" + calib, dev);
  EXPECT_EQ(unknown.status().message(), "v4l2: unknown option 'exposure'");
  auto one = openV4l2Source("/dev/video0?calib=" + calib, dev);
  EXPECT_NE(one.status().message().find("two devices"), std::string::npos);
  auto nocalib = openV4l2Source("/dev/video0,/dev/video1", dev);
  EXPECT_NE(nocalib.status().message().find("calib=FILE is required"), std::string::npos);
  auto badnum = openV4l2Source("/dev/video0,/dev/video1?width=8o&calib=" + calib, dev);
  EXPECT_NE(badnum.status().message().find("width='8o'"), std::string::npos);
  auto badfmt = openV4l2Source("/dev/video0,/dev/video1?format=RGB3&calib=" + calib, dev);
  EXPECT_NE(badfmt.status().message().find("RGB3"), std::string::npos);
  auto missing = openV4l2Source("/dev/video7,/dev/video8?width=80&height=60&calib=" + calib, dev);
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  auto layout = openV4l2Source("/dev/video0?layout=top-bottom&calib=" + calib, dev);
  EXPECT_NE(layout.status().message().find("top-bottom"), std::string::npos);
}

TEST(V4l2Source, PairingGivesUpWhenCamerasNeverAgree) {
  TimestampPairer pairer(kNsPerMs, 5);
  // Left at 0, 10, 20 ... ms; right at 5, 15, 25 ... ms: never within 1 ms.
  TimeNs next_t[2] = {0, 5 * kNsPerMs};
  auto grab = [&](int c, ImageU8& img, TimeNs& t) -> Result<bool> {
    img.resize(4, 4);
    t = next_t[c];
    next_t[c] += 10 * kNsPerMs;
    return true;
  };
  ImageU8 l, r;
  TimeNs t = 0;
  auto res = pairer.next(grab, l, r, t);
  ASSERT_FALSE(res);
  EXPECT_NE(res.status().message().find("not synchronised"), std::string::npos);
}

}  // namespace
}  // namespace svslam::drivers

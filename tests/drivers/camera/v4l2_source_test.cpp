// v4l2: stereo source on the fake driver: timestamp pairing with skew, side-by-side split,
// rectification from a calibration file written here, spec and calibration errors; injected
// faults: unplug and plug back (reconnect), never back, reconnect off, stop while waiting, a
// frozen camera.
#include "drivers/camera/v4l2_source.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
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

// Virtual time for the reconnect loop: waits advance it at once and are recorded.
class VirtualClock final : public ReconnectClock {
 public:
  TimeNs nowNs() override { return now; }
  bool waitNs(TimeNs ns, const StopQuery& stop) override {
    if (stop && stop()) return true;
    waits.push_back(ns);
    now += ns;
    if (on_wait) on_wait();
    return false;
  }
  TimeNs now = 1000 * kNsPerS;
  std::vector<TimeNs> waits;
  std::function<void()> on_wait;
};

constexpr TimeNs kP = 33'333'333;  // frame period at 30 Hz, ns

// Frames `first` .. `last` (inclusive) at 1 s + i kP, sequence i.
std::deque<FakeEvent> framesAt(int first, int last) {
  std::deque<FakeEvent> s;
  for (int i = first; i <= last; ++i)
    s.push_back(FakeEvent::frame(kNsPerS + i * kP, static_cast<std::uint32_t>(i)));
  return s;
}

std::deque<FakeEvent> concat(std::deque<FakeEvent> a, const std::deque<FakeEvent>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std::map<std::string, std::int64_t> counterMap(const StereoSource& src) {
  std::map<std::string, std::int64_t> m;
  for (const auto& [k, v] : src.counters()) m[k] = v;
  return m;
}

const std::string kPair = "/dev/video0,/dev/video1?width=80&height=60&calib=";

TEST(V4l2Source, UnpluggedCameraReconnectsAndFramesLostAreCounted) {
  FakeV4l2Device dev;
  // Frames 0..2, the left camera unplugged, both streaming again from frame 10 on.
  dev.addCamera(
      "/dev/video0",
      camera(kW, 0, concat(concat(framesAt(0, 2), {FakeEvent::enodev()}), framesAt(10, 12))));
  dev.addCamera("/dev/video1", camera(kW, 1, concat(framesAt(0, 2), framesAt(10, 12))));
  dev.camera("/dev/video0").replug_after_opens = 3;  // back at the 4th attempt
  VirtualClock clock;
  auto src = openV4l2Source(
      kPair + writeCalib("reconnect", kW, kH) + "&reconnect_timeout_s=5&reconnect_interval_ms=100",
      dev, {}, &clock);
  ASSERT_TRUE(src) << src.status().message();
  StereoFrame f;
  std::vector<TimeNs> t;
  for (int i = 0; i < 6; ++i) {
    auto r = (*src)->next(f);
    ASSERT_TRUE(r) << "pair " << i << ": " << r.status().message();
    ASSERT_TRUE(*r);
    EXPECT_EQ(f.index, i);
    t.push_back(f.t_ns);
  }
  EXPECT_EQ(
      t, (std::vector<TimeNs>{kNsPerS / 1000 * 1000, kNsPerS + kP / 1000 * 1000,
                              kNsPerS + 2 * kP / 1000 * 1000, kNsPerS + 10 * kP / 1000 * 1000,
                              kNsPerS + 11 * kP / 1000 * 1000, kNsPerS + 12 * kP / 1000 * 1000}));
  // Left frame 10 after the reconnect is the camera's live image again.
  EXPECT_LE(maxInteriorDiff(f.left, testing::expectedFrame(dev.camera("/dev/video0").base, 12)), 1);
  EXPECT_EQ(clock.waits, (std::vector<TimeNs>{100 * kNsPerMs, 100 * kNsPerMs, 100 * kNsPerMs}));
  EXPECT_EQ(dev.opens("/dev/video0"), 1 + 4);
  EXPECT_EQ(dev.opens("/dev/video1"), 1 + 1);  // reopened once the left one was back
  const auto c = counterMap(**src);
  EXPECT_EQ(c.at("reconnects"), 1);
  EXPECT_EQ(c.at("reconnect_frames_lost"), 7);  // frames 3..9
  EXPECT_EQ(c.at("reconnect_wait_ms"), 300);
  EXPECT_EQ(c.at("left_frames"), 6);
  EXPECT_EQ(c.at("right_frames"), 6);
  EXPECT_EQ(c.at("left_unpaired"), 0);
  EXPECT_EQ(c.at("right_unpaired"), 0);
  EXPECT_EQ((*src)->takeWarnings(),
            "device unplugged: /dev/video0: reconnecting (every 100 ms for up to 5 s)\n"
            "reconnected /dev/video0,/dev/video1 after 300 ms\n");
  EXPECT_EQ((*src)->takeWarnings(), "");
  EXPECT_EQ(dev.starved(), 0);
  src->reset();
  EXPECT_EQ(dev.openFds(), 0);
  EXPECT_EQ(dev.mappedBuffers(), 0);
}

TEST(V4l2Source, RightCameraAndSideBySideDeviceReconnectToo) {
  {
    FakeV4l2Device dev;
    dev.addCamera("/dev/video0", camera(kW, 0, concat(framesAt(0, 1), framesAt(5, 5))));
    dev.addCamera(
        "/dev/video1",
        camera(kW, 1, concat(concat(framesAt(0, 0), {FakeEvent::enodev()}), framesAt(5, 5))));
    dev.camera("/dev/video1").replug_after_opens = 1;
    dev.camera("/dev/video1").absent_errno = ENODEV;  // node still there, device gone
    VirtualClock clock;
    auto src = openV4l2Source(kPair + writeCalib("reconnect_r", kW, kH), dev, {}, &clock);
    ASSERT_TRUE(src) << src.status().message();
    StereoFrame f;
    for (int i = 0; i < 2; ++i) {
      auto r = (*src)->next(f);
      ASSERT_TRUE(r) << r.status().message();
    }
    EXPECT_EQ(f.t_ns, (kNsPerS + 5 * kP) / 1000 * 1000);
    const auto c = counterMap(**src);
    EXPECT_EQ(c.at("reconnects"), 1);
    EXPECT_EQ(c.at("reconnect_frames_lost"), 4);
    // The left head (frame 1) waiting for its partner was dropped with the restart.
    EXPECT_EQ(c.at("left_unpaired"), 0);
    EXPECT_EQ(clock.waits, (std::vector<TimeNs>{200 * kNsPerMs}));  // default interval
  }
  {
    FakeV4l2Device dev;
    dev.addCamera(
        "/dev/video2",
        camera(2 * kW, 3, concat(concat(framesAt(0, 0), {FakeEvent::enodev()}), framesAt(2, 2))));
    dev.camera("/dev/video2").replug_after_opens = 0;  // back at the first attempt
    VirtualClock clock;
    auto src = openV4l2Source("/dev/video2?layout=side-by-side&width=160&height=60&calib=" +
                                  writeCalib("reconnect_sbs", kW, kH),
                              dev, {}, &clock);
    ASSERT_TRUE(src) << src.status().message();
    StereoFrame f;
    ASSERT_TRUE((*src)->next(f));
    auto r = (*src)->next(f);
    ASSERT_TRUE(r) << r.status().message();
    EXPECT_EQ(f.index, 1);
    const auto c = counterMap(**src);
    EXPECT_EQ(c.at("reconnects"), 1);
    EXPECT_EQ(c.at("reconnect_frames_lost"), 1);
    EXPECT_EQ(c.at("reconnect_wait_ms"), 0);
    EXPECT_EQ(c.at("sbs_frames"), 2);
    EXPECT_TRUE(clock.waits.empty());
  }
}

// right_loss=left_only: the right camera unplugged after frame 2 and back after two failed
// reopens; the left camera goes on alone in between (frames with an empty right view), never
// waiting for the right one, and pairs resume when it is back.
TEST(V4l2Source, RightCameraLossGoesOnWithTheLeftAloneUntilItIsBack) {
  FakeV4l2Device dev;
  dev.addCamera("/dev/video0", camera(kW, 0, framesAt(0, 11)));
  dev.addCamera(
      "/dev/video1",
      camera(kW, 1, concat(concat(framesAt(0, 2), {FakeEvent::enodev()}), framesAt(9, 11))));
  dev.camera("/dev/video1").replug_after_opens = 2;  // back at the third attempt
  VirtualClock clock;
  auto src = openV4l2Source(kPair + writeCalib("right_loss", kW, kH) +
                                "&right_loss=left_only&reconnect_interval_ms=100",
                            dev, {}, &clock);
  ASSERT_TRUE(src) << src.status().message();
  StereoFrame f;
  for (int i = 0; i < 12; ++i) {
    if (i == 5 || i == 7 || i == 9) clock.now += 100 * kNsPerMs;  // a reopen attempt is due
    auto r = (*src)->next(f);
    ASSERT_TRUE(r) << "frame " << i << ": " << r.status().message();
    ASSERT_TRUE(*r);
    EXPECT_EQ(f.index, i);
    EXPECT_EQ(f.t_ns, (kNsPerS + i * kP) / 1000 * 1000) << "frame " << i;
    EXPECT_LE(maxInteriorDiff(f.left, testing::expectedFrame(dev.camera("/dev/video0").base,
                                                             static_cast<std::uint32_t>(i))),
              1)
        << "frame " << i;
    const bool alone = i >= 3 && i <= 8;  // the left frame waiting at the unplug included
    EXPECT_EQ(f.right.width() == 0 && f.right.height() == 0, alone) << "frame " << i;
    if (!alone) {
      EXPECT_LE(maxInteriorDiff(f.right, testing::expectedFrame(dev.camera("/dev/video1").base,
                                                                static_cast<std::uint32_t>(i))),
                1)
          << "frame " << i;
    }
  }
  EXPECT_TRUE(clock.waits.empty());  // never waited for the right camera
  EXPECT_EQ(dev.opens("/dev/video0"), 1);
  EXPECT_EQ(dev.opens("/dev/video1"), 1 + 3);
  const auto c = counterMap(**src);
  EXPECT_EQ(c.at("right_losses"), 1);
  EXPECT_EQ(c.at("left_only_frames"), 6);
  EXPECT_EQ(c.at("reconnects"), 0);
  EXPECT_EQ((*src)->takeWarnings(),
            "device unplugged: /dev/video1: going on with the left camera alone (reopening the "
            "right one every 100 ms)\n"
            "right camera back: /dev/video1 after 300 ms\n");
  src->reset();
  EXPECT_EQ(dev.openFds(), 0);
  EXPECT_EQ(dev.mappedBuffers(), 0);
}

TEST(V4l2Source, RightLossOptionIsChecked) {
  FakeV4l2Device dev;
  dev.addCamera("/dev/video0", camera(kW, 0, framesAt(0, 0)));
  dev.addCamera("/dev/video1", camera(kW, 1, framesAt(0, 0)));
  auto bad = openV4l2Source(kPair + writeCalib("right_loss_bad", kW, kH) + "&right_loss=maybe", dev);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.status().message().find("right_loss must be 'reconnect' or 'left_only'"),
            std::string::npos)
      << bad.status().message();
  auto sbs = openV4l2Source("/dev/video0?layout=side-by-side&width=160&height=60&right_loss="
                            "left_only&calib=" + writeCalib("right_loss_sbs", kW, kH),
                            dev);
  ASSERT_FALSE(sbs);
  EXPECT_NE(sbs.status().message().find("needs two cameras"), std::string::npos)
      << sbs.status().message();
}

TEST(V4l2Source, UnpluggedCameraNeverBackIsAnErrorAtTheTimeout) {
  FakeV4l2Device dev;
  dev.addCamera("/dev/video0", camera(kW, 0, concat(framesAt(0, 0), {FakeEvent::enodev()})));
  dev.addCamera("/dev/video1", camera(kW, 1, framesAt(0, 5)));
  VirtualClock clock;
  const TimeNs start = clock.now;
  auto src = openV4l2Source(
      kPair + writeCalib("never", kW, kH) + "&reconnect_timeout_s=1&reconnect_interval_ms=100", dev,
      {}, &clock);
  ASSERT_TRUE(src) << src.status().message();
  StereoFrame f;
  ASSERT_TRUE((*src)->next(f));
  auto r = (*src)->next(f);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().message(),
            "device unplugged: /dev/video0 (not back within 1 s, 11 attempts; last: no such "
            "video device: /dev/video0)");
  EXPECT_EQ(clock.now - start, kNsPerS);  // attempts at 0, 100, ..., 1000 ms
  EXPECT_EQ(clock.waits.size(), 10u);
  EXPECT_EQ(dev.opens("/dev/video0"), 1 + 11);
  EXPECT_EQ(counterMap(**src).at("reconnect_wait_ms"), 1000);
  EXPECT_EQ(dev.openFds(), 0);  // everything released
  EXPECT_EQ(dev.mappedBuffers(), 0);
  auto after = (*src)->next(f);  // the stream has ended
  ASSERT_TRUE(after);
  EXPECT_FALSE(*after);
}

TEST(V4l2Source, NeverBackOnTheRealClockEndsWithinTheTimeoutWithoutSpinning) {
  FakeV4l2Device dev;
  dev.addCamera("/dev/video0", camera(kW, 0, concat(framesAt(0, 0), {FakeEvent::enodev()})));
  dev.addCamera("/dev/video1", camera(kW, 1, framesAt(0, 5)));
  auto src = openV4l2Source(kPair + writeCalib("never_real", kW, kH) +
                                "&reconnect_timeout_s=0.2&reconnect_interval_ms=20",
                            dev);
  ASSERT_TRUE(src) << src.status().message();
  StereoFrame f;
  ASSERT_TRUE((*src)->next(f));
  const auto t0 = std::chrono::steady_clock::now();
  auto r = (*src)->next(f);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().message().rfind("device unplugged: /dev/video0 (not back within 0.2 s, ", 0),
            0u)
      << r.status().message();
  EXPECT_GE(s, 0.2);
  EXPECT_LT(s, 5.0);  // generous: a loaded 2-core machine
  EXPECT_GE(dev.opens("/dev/video0"), 1 + 2);
  EXPECT_LE(dev.opens("/dev/video0"), 1 + 11);  // one attempt per interval, no busy loop
}

TEST(V4l2Source, ReconnectOffIsAnImmediateCleanError) {
  FakeV4l2Device dev;
  dev.addCamera("/dev/video0", camera(kW, 0, concat(framesAt(0, 0), {FakeEvent::enodev()})));
  dev.addCamera("/dev/video1", camera(kW, 1, framesAt(0, 5)));
  dev.camera("/dev/video0").replug_after_opens = 0;  // would be back at once: not tried
  VirtualClock clock;
  auto src =
      openV4l2Source(kPair + writeCalib("off", kW, kH) + "&reconnect_timeout_s=0", dev, {}, &clock);
  ASSERT_TRUE(src) << src.status().message();
  StereoFrame f;
  ASSERT_TRUE((*src)->next(f));
  auto r = (*src)->next(f);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().message(), "device unplugged: /dev/video0");
  EXPECT_EQ(dev.opens("/dev/video0"), 1);
  EXPECT_TRUE(clock.waits.empty());
  EXPECT_EQ(counterMap(**src).at("reconnects"), 0);
}

TEST(V4l2Source, StopRequestWhileWaitingEndsTheStream) {
  FakeV4l2Device dev;
  dev.addCamera("/dev/video0", camera(kW, 0, concat(framesAt(0, 0), {FakeEvent::enodev()})));
  dev.addCamera("/dev/video1", camera(kW, 1, framesAt(0, 5)));
  VirtualClock clock;
  bool stop = false;
  clock.on_wait = [&] { stop = clock.waits.size() == 3; };
  auto src = openV4l2Source(
      kPair + writeCalib("stop", kW, kH), dev, [&] { return stop; }, &clock);
  ASSERT_TRUE(src) << src.status().message();
  StereoFrame f;
  ASSERT_TRUE((*src)->next(f));
  auto r = (*src)->next(f);
  ASSERT_TRUE(r) << r.status().message();
  EXPECT_FALSE(*r);  // ended, not an error
  EXPECT_EQ(clock.waits.size(), 3u);
  EXPECT_EQ(dev.opens("/dev/video0"), 1 + 3);
  EXPECT_EQ(counterMap(**src).at("reconnects"), 1);
}

TEST(V4l2Source, FrozenCameraEndsTheRunAfterExactlyNFrames) {
  FakeV4l2Device dev;
  dev.addCamera("/dev/video0", camera(kW, 0, framesAt(0, 40)));
  dev.addCamera("/dev/video1", camera(kW, 1, framesAt(0, 40)));
  dev.camera("/dev/video1").freeze_from_sequence = 5;  // the right camera shows frame 5 forever
  auto src = openV4l2Source(kPair + writeCalib("frozen", kW, kH) + "&frozen_frames=10", dev);
  ASSERT_TRUE(src) << src.status().message();
  StereoFrame f;
  for (int i = 0; i < 14; ++i) {  // pairs 5..13: 9 identical right frames, not yet frozen
    auto r = (*src)->next(f);
    ASSERT_TRUE(r) << "pair " << i << ": " << r.status().message();
  }
  auto r = (*src)->next(f);  // pair 14: the 10th identical frame
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().message(),
            "camera frozen: /dev/video1 delivered the same image for 10 frames");
  auto* v4l2 = dynamic_cast<V4l2StereoSource*>(src->get());
  ASSERT_NE(v4l2, nullptr);
  EXPECT_EQ(v4l2->frozenDetections(0), 0u);
  EXPECT_EQ(v4l2->frozenDetections(1), 1u);
}

TEST(V4l2Source, FrozenCameraDefaultsTo30FramesAndWarnGoesOn) {
  {
    FakeV4l2Device dev;
    dev.addCamera("/dev/video0", camera(kW, 0, framesAt(0, 40)));
    dev.addCamera("/dev/video1", camera(kW, 1, framesAt(0, 40)));
    dev.camera("/dev/video0").freeze_from_sequence = 0;  // same buffer from the start
    auto src = openV4l2Source(kPair + writeCalib("frozen30", kW, kH), dev);
    ASSERT_TRUE(src) << src.status().message();
    StereoFrame f;
    int delivered = 0;
    Result<bool> r = true;
    while ((r = (*src)->next(f)) && *r) ++delivered;
    ASSERT_FALSE(r);
    EXPECT_EQ(delivered, 29);
    EXPECT_EQ(r.status().message(),
              "camera frozen: /dev/video0 delivered the same image for 30 frames");
  }
  {
    FakeV4l2Device dev;
    dev.addCamera("/dev/video0", camera(kW, 0, framesAt(0, 40)));
    dev.addCamera("/dev/video1", camera(kW, 1, framesAt(0, 40)));
    dev.camera("/dev/video0").freeze_from_sequence = 20;
    auto src = openV4l2Source(
        kPair + writeCalib("frozen_warn", kW, kH) + "&frozen_frames=5&frozen_action=warn", dev);
    ASSERT_TRUE(src) << src.status().message();
    StereoFrame f;
    for (int i = 0; i <= 40; ++i) {
      auto r = (*src)->next(f);
      ASSERT_TRUE(r) << r.status().message();
      ASSERT_TRUE(*r);
    }
    EXPECT_EQ((*src)->takeWarnings(),
              "camera frozen: /dev/video0 delivered the same image for 5 frames\n");
    const auto c = counterMap(**src);
    EXPECT_EQ(c.at("left_frozen"), 1);
    EXPECT_EQ(c.at("right_frozen"), 0);
    EXPECT_EQ(c.at("left_max_identical_run"), 21);  // frames 20..40
    EXPECT_EQ(c.at("right_max_identical_run"), 1);
  }
  {  // off: a frozen camera goes unnoticed
    FakeV4l2Device dev;
    dev.addCamera("/dev/video0", camera(kW, 0, framesAt(0, 40)));
    dev.addCamera("/dev/video1", camera(kW, 1, framesAt(0, 40)));
    dev.camera("/dev/video0").freeze_from_sequence = 0;
    auto src = openV4l2Source(kPair + writeCalib("frozen_off", kW, kH) + "&frozen_frames=0", dev);
    ASSERT_TRUE(src) << src.status().message();
    StereoFrame f;
    for (int i = 0; i <= 40; ++i) ASSERT_TRUE((*src)->next(f));
    EXPECT_EQ(counterMap(**src).at("left_frozen"), 0);
  }
}

TEST(V4l2Source, FaultOptionsOutOfRangeNameTheKey) {
  FakeV4l2Device dev;
  const std::string base = kPair + writeCalib("fault_opts", kW, kH);
  auto msg = [&](const std::string& opt) {
    auto r = openV4l2Source(base + "&" + opt, dev);
    EXPECT_FALSE(r) << opt;
    return r ? std::string() : r.status().message();
  };
  EXPECT_EQ(msg("reconnect_timeout_s=-1"),
            "v4l2: option reconnect_timeout_s must be in [0, 3600] s, got -1");
  EXPECT_EQ(msg("reconnect_timeout_s=5s"), "v4l2: option reconnect_timeout_s='5s' is not a number");
  EXPECT_EQ(msg("reconnect_interval_ms=5"),
            "v4l2: option reconnect_interval_ms must be in [10, 60000] ms, got 5");
  EXPECT_EQ(msg("reconnect_interval_ms=2.5"),
            "v4l2: option reconnect_interval_ms must be an integer");
  EXPECT_EQ(msg("frozen_frames=1"),
            "v4l2: option frozen_frames must be 0 (off) or in [2, 1000000], got 1");
  EXPECT_EQ(msg("frozen_action=stop"),
            "v4l2: option frozen_action must be 'error' or 'warn', got 'stop'");
  EXPECT_EQ(msg("max_bad_buffers=10001"),
            "v4l2: option max_bad_buffers must be in [0, 10000], got 10001");
  EXPECT_EQ(dev.openFds(), 0);
  auto setup = parseV4l2Setup("/dev/video0,/dev/video1");
  ASSERT_TRUE(setup);
  EXPECT_EQ(setup->reconnect.timeout_s, 5.0);
  EXPECT_EQ(setup->reconnect.interval_ms, 200);
  EXPECT_EQ(setup->frozen.detector.frozen_frames, 30);
  EXPECT_TRUE(setup->frozen.end_run);
  EXPECT_EQ(setup->params.max_bad_buffers, 30);
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

// V4l2Capture against the scripted fake driver: content, timestamps, buffer requeueing,
// recovery (EAGAIN, EIO, FLAG_ERROR), unplug, timeout, granted-format mismatch, bad params.
#include "drivers/camera/v4l2_capture.hpp"

#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <cerrno>
#include <cstdlib>
#include <utility>

#include "fake_v4l2_device.hpp"

namespace svslam::drivers {
namespace {

using testing::FakeCameraConfig;
using testing::FakeEvent;
using testing::FakeV4l2Device;

constexpr int kW = 64, kH = 48;
const char* kDev = "/dev/video0";

V4l2CaptureParams params(const std::string& format = "GREY") {
  V4l2CaptureParams p;
  p.device = kDev;
  p.width = kW;
  p.height = kH;
  p.format = format;
  p.buffers = 3;
  return p;
}

FakeCameraConfig camera(std::deque<FakeEvent> script) {
  FakeCameraConfig c;
  c.base = testing::testPattern(kW, kH);
  c.script = std::move(script);
  return c;
}

// 10 frames at 30 Hz starting at 5 s, sequence 0..9.
std::deque<FakeEvent> frames(int n, std::uint32_t first_seq = 0) {
  std::deque<FakeEvent> s;
  for (int i = 0; i < n; ++i)
    s.push_back(FakeEvent::frame(5 * kNsPerS + i * 33'333'333, first_seq + i));
  return s;
}

// One fake camera playing `script` on kDev, a capture opened on it, and the outputs of grab.
struct OpenCapture {
  explicit OpenCapture(std::deque<FakeEvent> script, int max_bad_buffers = -1)
      : cap(dev, [&] {
          V4l2CaptureParams p = params();
          if (max_bad_buffers >= 0) p.max_bad_buffers = max_bad_buffers;
          return p;
        }()) {
    dev.addCamera(kDev, camera(std::move(script)));
    opened = cap.open();
  }
  Result<bool> grab() { return cap.grab(img, t, seq); }
  FakeV4l2Device dev;
  V4l2Capture cap;
  Status opened;
  ImageU8 img;
  TimeNs t = 0;
  std::uint32_t seq = 0;
};

double meanAbsDiff(const ImageU8& a, const ImageU8& b) {
  double sum = 0;
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) sum += std::abs(a(x, y) - b(x, y));
  return sum / (a.width() * a.height());
}

class CaptureFormats : public ::testing::TestWithParam<const char*> {};

TEST_P(CaptureFormats, FramesArriveInOrderAndBuffersAreRequeued) {
  FakeV4l2Device dev;
  FakeCameraConfig cfg = camera(frames(10));
  cfg.row_padding = 13;  // odd stride for GREY / YUYV
  dev.addCamera(kDev, std::move(cfg));
  {
    V4l2Capture cap(dev, params(GetParam()));
    ASSERT_TRUE(cap.open());
    ASSERT_TRUE(dev.streaming(kDev));
    ImageU8 img;
    TimeNs t = 0, last_t = 0;
    std::uint32_t seq = 0;
    for (std::uint32_t i = 0; i < 10; ++i) {  // more frames than the 3 buffers
      auto r = cap.grab(img, t, seq);
      ASSERT_TRUE(r) << r.status().message();
      ASSERT_TRUE(*r);
      EXPECT_EQ(seq, i);
      EXPECT_EQ(t, 5 * kNsPerS + static_cast<TimeNs>(i) * 33'333'333 / 1000 * 1000);
      if (i > 0) {
        EXPECT_GT(t, last_t);
      }
      last_t = t;
      const ImageU8 want = testing::expectedFrame(dev.camera(kDev).base, i);
      ASSERT_EQ(img.width(), kW);
      ASSERT_EQ(img.height(), kH);
      const double tolerance = std::string(GetParam()) == "MJPEG" ? 2.0 : 0.0;
      EXPECT_LE(meanAbsDiff(img, want), tolerance);
    }
    EXPECT_EQ(cap.stats().frames, 10u);
    EXPECT_EQ(dev.starved(), 0);
    EXPECT_EQ(dev.queued(kDev), 3 + 10);
    // The script is exhausted: the next grab times out, naming the device.
    auto r = cap.grab(img, t, seq);
    ASSERT_FALSE(r);
    EXPECT_NE(r.status().message().find("timeout"), std::string::npos);
    EXPECT_NE(r.status().message().find(kDev), std::string::npos);
  }
  // The destructor stopped streaming, unmapped and closed.
  EXPECT_FALSE(dev.streaming(kDev));
  EXPECT_EQ(dev.mappedBuffers(), 0);
  EXPECT_EQ(dev.openFds(), 0);
}

INSTANTIATE_TEST_SUITE_P(AllFormats, CaptureFormats, ::testing::Values("GREY", "YUYV", "MJPEG"));

TEST(V4l2Capture, RecoversFromEagainAndDropsErroredBuffers) {
  OpenCapture c({FakeEvent::frame(1000, 0), FakeEvent::eagain(), FakeEvent::eagain(),
                 FakeEvent::frame(2000, 1), FakeEvent::eio(), FakeEvent::errorFlag(3000, 2),
                 FakeEvent::frame(4000, 3), FakeEvent::frame(5000, 4), FakeEvent::frame(6000, 5),
                 FakeEvent::frame(7000, 6)});
  ASSERT_TRUE(c.opened);
  std::vector<std::uint32_t> got;
  for (int i = 0; i < 6; ++i) {
    auto r = c.grab();
    ASSERT_TRUE(r) << r.status().message();
    got.push_back(c.seq);
  }
  EXPECT_EQ(got, (std::vector<std::uint32_t>{0, 1, 3, 4, 5, 6}));
  EXPECT_EQ(c.cap.stats().retries, 2u);
  EXPECT_EQ(c.cap.stats().dropped, 2u);
  EXPECT_EQ(c.cap.stats().sequence_gaps, 1u);  // sequence 2 never delivered
  EXPECT_EQ(c.dev.starved(), 0);               // EIO and FLAG_ERROR buffers went back
}

TEST(V4l2Capture, TooManyBadBuffersInARowIsAnError) {
  OpenCapture c({FakeEvent::eio(), FakeEvent::errorFlag(1, 0), FakeEvent::eio(), FakeEvent::eio(),
                 FakeEvent::frame(10, 1)},
                3);
  ASSERT_TRUE(c.opened);
  auto r = c.grab();
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("4 bad buffers in a row"), std::string::npos)
      << r.status().message();
  // Streaming goes on: the next frame is still delivered.
  auto again = c.grab();
  ASSERT_TRUE(again) << again.status().message();
  EXPECT_EQ(c.seq, 1u);
}

// A burst of K EIO dequeues between frames 0..2 and 3..5: every frame comes through in order,
// exactly K buffers are dropped and requeued, for K up to the limit max_bad_buffers.
class EioBurst : public ::testing::TestWithParam<int> {};

TEST_P(EioBurst, FramesAfterTheBurstComeThroughAndDropsAreCountedExactly) {
  const int k = GetParam();
  std::deque<FakeEvent> script = frames(3);
  for (int i = 0; i < k; ++i) script.push_back(FakeEvent::eio());
  for (const FakeEvent& f : frames(3, 3))
    script.push_back(FakeEvent::frame(f.t_ns + kNsPerS, f.sequence));
  OpenCapture c(std::move(script), 100);
  ASSERT_TRUE(c.opened);
  std::vector<std::uint32_t> got;
  for (int i = 0; i < 6; ++i) {
    auto r = c.grab();
    ASSERT_TRUE(r) << "K " << k << ": " << r.status().message();
    ASSERT_TRUE(*r);
    got.push_back(c.seq);
    EXPECT_EQ(c.img.width(), kW);
  }
  EXPECT_EQ(got, (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(c.cap.stats().dropped, static_cast<std::uint64_t>(k));
  EXPECT_EQ(c.cap.stats().frames, 6u);
  EXPECT_EQ(c.cap.stats().retries, 0u);
  EXPECT_EQ(c.dev.starved(), 0);  // every EIO buffer went back to the driver
  EXPECT_EQ(c.dev.dequeued(kDev), 6 + k);
  EXPECT_EQ(c.dev.queued(kDev), 3 + 6 + k);
}

INSTANTIATE_TEST_SUITE_P(K, EioBurst, ::testing::Values(1, 10, 100));

TEST(V4l2Capture, EioBurstLongerThanTheLimitIsAnErrorNamingTheDevice) {
  for (const auto& [limit, burst] : {std::pair{100, 101}, std::pair{30, 31}, std::pair{3, 4}}) {
    std::deque<FakeEvent> script = frames(1);
    for (int i = 0; i < burst + 5; ++i) script.push_back(FakeEvent::eio());
    script.push_back(FakeEvent::frame(9 * kNsPerS, 50));
    OpenCapture c(std::move(script), limit == 30 ? -1 : limit);  // 30: the default
    ASSERT_TRUE(c.opened);
    ASSERT_TRUE(c.grab());
    auto r = c.grab();
    ASSERT_FALSE(r) << "limit " << limit;
    EXPECT_EQ(r.status().message(), "/dev/video0: " + std::to_string(burst) +
                                        " bad buffers in a row (last: VIDIOC_DQBUF: EIO)");
    EXPECT_EQ(c.cap.stats().dropped, static_cast<std::uint64_t>(burst));
    EXPECT_EQ(c.dev.starved(), 0);
  }
}

TEST(V4l2Capture, EndlessBadBuffersEndAtTimeoutMs) {
  // A driver returning an errored buffer every >= 1 ms, limit not reached: the call gives up
  // after timeout_ms (20 ms) with the count of bad buffers, instead of looping on.
  FakeV4l2Device dev;
  std::deque<FakeEvent> script;
  for (int i = 0; i < 5000; ++i) script.push_back(FakeEvent::eio());
  dev.addCamera(kDev, camera(std::move(script)));
  dev.setPollSleepUs(1000);
  V4l2CaptureParams p = params();
  p.max_bad_buffers = 10000;
  p.timeout_ms = 20;
  V4l2Capture cap(dev, p);
  ASSERT_TRUE(cap.open());
  ImageU8 img;
  TimeNs t = 0;
  std::uint32_t seq = 0;
  auto r = cap.grab(img, t, seq);
  ASSERT_FALSE(r);
  const std::uint64_t bad = cap.stats().dropped;
  EXPECT_GE(bad, 1u);
  EXPECT_LE(bad, 21u);  // each poll sleeps >= 1 ms: at most 21 polls fit in 20 ms
  EXPECT_EQ(r.status().message(), "timeout: no frame from /dev/video0 within 20 ms (" +
                                      std::to_string(bad) + " bad buffers)");
}

TEST(V4l2Capture, UnplugIsACleanError) {
  OpenCapture c({FakeEvent::frame(10, 0), FakeEvent::enodev()});
  ASSERT_TRUE(c.opened);
  ASSERT_TRUE(c.grab());
  auto r = c.grab();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().message(), "device unplugged: /dev/video0");
  EXPECT_TRUE(c.cap.unplugged());
  auto after = c.grab();  // no longer streaming
  ASSERT_TRUE(after);
  EXPECT_FALSE(*after);
  EXPECT_TRUE(c.cap.stop());
  EXPECT_EQ(c.dev.openFds(), 0);
  EXPECT_EQ(c.dev.mappedBuffers(), 0);
}

TEST(V4l2Capture, ReopensAfterTheDeviceIsBack) {
  OpenCapture c({FakeEvent::frame(10'000, 0), FakeEvent::enodev(), FakeEvent::frame(20'000, 0)});
  c.dev.camera(kDev).replug_after_opens = 2;
  ASSERT_TRUE(c.opened);
  ASSERT_TRUE(c.grab());
  ASSERT_FALSE(c.grab());
  ASSERT_TRUE(c.cap.stop());
  const Status gone1 = c.cap.open();
  EXPECT_EQ(gone1.code(), StatusCode::kNotFound);
  EXPECT_EQ(gone1.message(), "no such video device: /dev/video0");
  c.dev.camera(kDev).absent_errno = ENODEV;
  EXPECT_EQ(c.cap.open().message(), "cannot open /dev/video0: No such device");
  EXPECT_EQ(c.dev.openFds(), 0);
  ASSERT_TRUE(c.cap.open());  // third attempt: back
  EXPECT_FALSE(c.cap.unplugged());
  auto r = c.grab();
  ASSERT_TRUE(r) << r.status().message();
  ASSERT_TRUE(*r);
  EXPECT_EQ(c.t, 20'000);  // us resolution (timeval)
  EXPECT_EQ(c.cap.stats().frames, 2u);
  EXPECT_EQ(c.dev.opens(kDev), 4);
  EXPECT_EQ(c.dev.starved(), 0);
}

TEST(V4l2Capture, TimeoutNamesTheDevice) {
  OpenCapture c({FakeEvent::timeout(), FakeEvent::frame(10, 0)});
  ASSERT_TRUE(c.opened);
  auto r = c.grab();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.status().message(), "timeout: no frame from /dev/video0 within 1000 ms");
  EXPECT_TRUE(c.grab());  // a late camera can still deliver
}

TEST(V4l2Capture, NonMonotonicTimestampsAreDropped) {
  OpenCapture c({FakeEvent::frame(2000, 0), FakeEvent::frame(1000, 1), FakeEvent::frame(3000, 2)});
  ASSERT_TRUE(c.opened);
  ASSERT_TRUE(c.grab());
  ASSERT_TRUE(c.grab());
  EXPECT_EQ(c.seq, 2u);
  EXPECT_EQ(c.cap.stats().non_monotonic, 1u);
}

TEST(V4l2Capture, GrantedFormatMismatchIsAnError) {
  FakeV4l2Device dev;
  FakeCameraConfig cfg = camera(frames(2));
  cfg.granted_width = 320;
  cfg.granted_height = 240;
  dev.addCamera(kDev, std::move(cfg));
  V4l2Capture cap(dev, params());
  const Status s = cap.open();
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("asked for 64x48 GREY, driver granted 320x240 GREY"),
            std::string::npos)
      << s.message();
  EXPECT_EQ(dev.openFds(), 0);  // cleaned up after the failed open

  FakeCameraConfig yuyv = camera(frames(2));
  yuyv.granted_fourcc = V4L2_PIX_FMT_YUYV;
  dev.addCamera(kDev, std::move(yuyv));
  const Status f = V4l2Capture(dev, params("MJPEG")).open();
  EXPECT_NE(f.message().find("granted 64x48 YUYV"), std::string::npos) << f.message();
}

TEST(V4l2Capture, OpenErrors) {
  FakeV4l2Device dev;
  EXPECT_EQ(V4l2Capture(dev, params()).open().code(), StatusCode::kNotFound);
  FakeCameraConfig out = camera({});
  out.capabilities = V4L2_CAP_VIDEO_OUTPUT | V4L2_CAP_STREAMING;
  dev.addCamera(kDev, std::move(out));
  const Status s = V4l2Capture(dev, params()).open();
  EXPECT_NE(s.message().find("not a video capture device"), std::string::npos) << s.message();
  EXPECT_EQ(dev.openFds(), 0);
}

TEST(V4l2Capture, BadParamsAreRejected) {
  auto bad = [](auto mutate) {
    V4l2CaptureParams p = params();
    mutate(p);
    return p.validate();
  };
  EXPECT_TRUE(params().validate());
  EXPECT_FALSE(bad([](V4l2CaptureParams& p) { p.device.clear(); }));
  EXPECT_FALSE(bad([](V4l2CaptureParams& p) { p.width = 0; }));
  EXPECT_FALSE(bad([](V4l2CaptureParams& p) { p.fps = -1; }));
  EXPECT_FALSE(bad([](V4l2CaptureParams& p) { p.format = "RGB24"; }));
  EXPECT_FALSE(bad([](V4l2CaptureParams& p) { p.buffers = 1; }));
  EXPECT_FALSE(bad([](V4l2CaptureParams& p) { p.timeout_ms = 0; }));
  EXPECT_FALSE(bad([](V4l2CaptureParams& p) { p.max_bad_buffers = -1; }));
  EXPECT_FALSE(bad([](V4l2CaptureParams& p) { p.max_bad_buffers = 10001; }));
  EXPECT_EQ(V4l2CaptureParams().max_bad_buffers, 30);
  FakeV4l2Device dev;
  V4l2CaptureParams p = params();
  p.buffers = 0;
  const Status s = V4l2Capture(dev, p).open();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("buffers"), std::string::npos);
}

}  // namespace
}  // namespace svslam::drivers

// The lcm: stereo source fed by a publisher thread over memq://: order, calibration from the
// first message, skipped wrong-size / malformed frames, bounded queue, timeouts.
#include "drivers/lcm/lcm_source.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

namespace svslam::drivers {
namespace {

using namespace std::chrono_literals;

StereoCalibration calib(int w, int h) {
  StereoCalibration c;
  c.f_px = 300.0;
  c.cx_px = w / 2.0;
  c.cy_px = h / 2.0;
  c.baseline_m = 0.1;
  c.width = w;
  c.height = h;
  return c;
}

svslam_lcm::stereo_image_t frame(int seq, const StereoCalibration& c) {
  ImageU8 l(c.width, c.height), r(c.width, c.height);
  l.fill(std::uint8_t(seq));
  r.fill(std::uint8_t(100 + seq));
  return toLcmStereoImage(l, r, c, TimeNs(seq) * 100'000'000 + 5'000, seq).value();
}

LcmSourceParams params(double timeout_s = 0.5) {
  LcmSourceParams p;
  p.channel = "CAM";
  p.timeout_s = timeout_s;
  return p;
}

std::unique_ptr<LcmLink> memqLink() {
  LcmParams p;
  p.url = "memq://";
  return std::move(LcmLink::open(p).value());
}

TEST(LcmSource, SpecParsing) {
  auto p = parseLcmSourceSpec("STEREO?timeout_s=2.5&queue=8&url=udpm://239.255.76.67:7667?ttl=0");
  ASSERT_TRUE(p.isOk()) << p.status().message();
  EXPECT_EQ(p->channel, "STEREO");
  EXPECT_EQ(p->timeout_s, 2.5);
  EXPECT_EQ(p->queue_capacity, 8);
  EXPECT_EQ(p->url, "udpm://239.255.76.67:7667?ttl=0");
  auto d = parseLcmSourceSpec("STEREO");
  ASSERT_TRUE(d.isOk());
  EXPECT_EQ(d->timeout_s, 10.0);
  EXPECT_FALSE(parseLcmSourceSpec("").isOk());
  EXPECT_FALSE(parseLcmSourceSpec("A?timeout_s=-1").isOk());
  EXPECT_FALSE(parseLcmSourceSpec("A?timeout_s=x").isOk());
  EXPECT_FALSE(parseLcmSourceSpec("A?colour=red").isOk());
}

TEST(LcmSource, FramesInOrderCalibrationFromFirstWrongSizeSkippedTimeoutEnds) {
  auto link = memqLink();
  const auto c = calib(32, 24);
  std::thread pub([&] {
    std::this_thread::sleep_for(100ms);  // after the source subscribed
    for (int i = 0; i < 6; ++i) {
      if (i == 3) {  // another size, then garbage: both skipped
        ASSERT_TRUE(link->publishStereoImage("CAM", frame(99, calib(16, 24))).isOk());
        const std::uint8_t junk[] = {9, 9, 9, 9, 9, 9, 9, 9, 9};
        ASSERT_TRUE(link->publishRaw("CAM", junk, sizeof junk).isOk());
      }
      ASSERT_TRUE(link->publishStereoImage("CAM", frame(i, c)).isOk());
      std::this_thread::sleep_for(10ms);
    }
  });
  auto src = openLcmSource(params(), *link);
  ASSERT_TRUE(src.isOk()) << src.status().message();
  const auto& got = (*src)->calibration();
  EXPECT_EQ(got.width, 32);
  EXPECT_EQ(got.height, 24);
  EXPECT_EQ(got.f_px, 300.0);
  EXPECT_EQ(got.baseline_m, 0.1);
  EXPECT_EQ((*src)->size(), -1);
  StereoFrame f;
  for (int i = 0; i < 6; ++i) {
    auto more = (*src)->next(f);
    ASSERT_TRUE(more.isOk()) << more.status().message();
    ASSERT_TRUE(*more) << "frame " << i;
    EXPECT_EQ(f.index, i);
    EXPECT_EQ(f.t_ns, TimeNs(i) * 100'000'000 + 5'000);
    EXPECT_EQ(f.left(5, 7), i);
    EXPECT_EQ(f.right(31, 23), 100 + i);
  }
  pub.join();
  const auto t0 = std::chrono::steady_clock::now();
  auto end = (*src)->next(f);
  ASSERT_TRUE(end.isOk());
  EXPECT_FALSE(*end);  // the timeout ends the sequence
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 450ms);
  auto* lcm_src = dynamic_cast<LcmStereoSource*>(src->get());
  ASSERT_NE(lcm_src, nullptr);
  EXPECT_EQ(lcm_src->mismatchCount(), 1);
  EXPECT_EQ(lcm_src->malformedCount(), 1);
  EXPECT_EQ(lcm_src->droppedCount(), 0);
}

TEST(LcmSource, NoImageWithinTimeoutIsAClearError) {
  auto link = memqLink();
  auto src = openLcmSource(params(0.2), *link);
  ASSERT_FALSE(src.isOk());
  EXPECT_NE(src.status().message().find("lcm:CAM: no stereo_image_t received within 0.2 s"),
            std::string::npos)
      << src.status().message();
}

TEST(LcmSource, SlowConsumerKeepsNewestFramesOnly) {
  auto link = memqLink();
  const auto c = calib(8, 8);
  auto p = params();
  p.queue_capacity = 2;
  std::thread first([&] {
    std::this_thread::sleep_for(100ms);
    ASSERT_TRUE(link->publishStereoImage("CAM", frame(0, c)).isOk());
  });
  auto src = openLcmSource(p, *link);
  first.join();
  ASSERT_TRUE(src.isOk()) << src.status().message();
  for (int i = 1; i < 10; ++i) {
    ASSERT_TRUE(link->publishStereoImage("CAM", frame(i, c)).isOk());
    std::this_thread::sleep_for(5ms);  // the receiver thread handles each one
  }
  std::this_thread::sleep_for(100ms);
  StereoFrame f;
  ASSERT_TRUE((*src)->next(f).value());
  EXPECT_EQ(f.left(0, 0), 8);
  ASSERT_TRUE((*src)->next(f).value());
  EXPECT_EQ(f.left(0, 0), 9);
  EXPECT_EQ(dynamic_cast<LcmStereoSource*>(src->get())->droppedCount(), 8);
}

TEST(LcmSource, OpenStereoSourceDispatchesLcmPrefix) {
  auto bad = openStereoSource("lcm:CAM?timeout_s=0.1&url=bogus://x");
  ASSERT_FALSE(bad.isOk());
  EXPECT_NE(bad.status().message().find("'bogus://x'"), std::string::npos)
      << bad.status().message();
  auto none = openStereoSource("lcm:CAM?timeout_s=0.2&url=memq://");
  ASSERT_FALSE(none.isOk());
  EXPECT_NE(none.status().message().find("no stereo_image_t"), std::string::npos);
}

}  // namespace
}  // namespace svslam::drivers

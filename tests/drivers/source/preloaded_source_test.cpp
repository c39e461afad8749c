// A sequence read into memory, replayed once or in a loop (soak tests): indices and stamps run
// on across the replays, the pixels are the stored ones, and bad loop counts are refused.
#include "drivers/source/preloaded_source.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace svslam::drivers {
namespace {

bool samePixels(const ImageU8& a, const ImageU8& b) {
  if (a.width() != b.width() || a.height() != b.height()) return false;
  for (int y = 0; y < a.height(); ++y)
    if (std::memcmp(a.row(y), b.row(y), static_cast<std::size_t>(a.width())) != 0) return false;
  return true;
}

TEST(PreloadedSource, LoopsContinueIndexAndClock) {
  auto src = openStereoSource("synthetic:width=96,height=72,frames=4");
  ASSERT_TRUE(src.isOk()) << src.status().message();
  auto pre = preload(std::move(*src), 0);
  ASSERT_TRUE(pre.isOk()) << pre.status().message();
  PreloadedSource& p = **pre;
  ASSERT_EQ(p.size(), 4);
  std::vector<StereoFrame> once(4);
  for (StereoFrame& f : once) ASSERT_TRUE(p.next(f).value());
  StereoFrame extra;
  EXPECT_FALSE(p.next(extra).value());  // one replay by default
  const TimeNs dt = once[3].t_ns - once[2].t_ns;
  ASSERT_GT(dt, 0);
  const TimeNs period = once[3].t_ns - once[0].t_ns + dt;

  ASSERT_TRUE(p.setLoops(3).isOk());
  EXPECT_EQ(p.size(), 12);
  p.rewind();
  StereoFrame f;
  TimeNs last_t = -1;
  for (int k = 0; k < 12; ++k) {
    ASSERT_TRUE(p.next(f).value()) << k;
    EXPECT_EQ(f.index, k);
    EXPECT_EQ(f.t_ns, once[k % 4].t_ns + (k / 4) * period);
    EXPECT_GT(f.t_ns, last_t);  // the clock never steps back at a wrap
    last_t = f.t_ns;
    EXPECT_TRUE(samePixels(f.left, once[k % 4].left) && samePixels(f.right, once[k % 4].right));
  }
  EXPECT_FALSE(p.next(f).value());
  Eigen::Isometry3d T;
  EXPECT_TRUE(p.groundTruth(3, T));
}

TEST(PreloadedSource, BadLoopCountsAreRefused) {
  auto src = openStereoSource("synthetic:width=96,height=72,frames=1");
  ASSERT_TRUE(src.isOk());
  auto pre = preload(std::move(*src), 0);
  ASSERT_TRUE(pre.isOk());
  EXPECT_TRUE((*pre)->setLoops(1).isOk());
  const Status zero = (*pre)->setLoops(0);
  EXPECT_FALSE(zero.isOk());
  EXPECT_NE(zero.message().find("[1, 1000000]"), std::string::npos) << zero.message();
  const Status single = (*pre)->setLoops(2);  // one frame: no interval to continue the clock
  EXPECT_FALSE(single.isOk());
  EXPECT_NE(single.message().find("at least 2 frames"), std::string::npos) << single.message();
  EXPECT_EQ((*pre)->size(), 1);
}

}  // namespace
}  // namespace svslam::drivers

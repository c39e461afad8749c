// FrozenFrameDetector: detection at exactly N identical frames, one changed pixel resets the run,
// once per run, size changes, strided views, off, bad parameters.
#include "core/frozen_frame_detector.hpp"

#include <gtest/gtest.h>

namespace svslam {
namespace {

ImageU8 pattern(int w, int h, int seed) {
  ImageU8 img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img(x, y) = static_cast<std::uint8_t>((x * 7 + y * 13 + seed) & 0xFF);
  return img;
}

FrozenFrameDetector detector(int n) {
  FrozenFrameParams p;
  p.frozen_frames = n;
  return FrozenFrameDetector(p);
}

TEST(FrozenFrameDetector, IdenticalFramesAreDetectedAtExactlyN) {
  for (int n : {2, 3, 30}) {
    FrozenFrameDetector d = detector(n);
    const ImageU8 img = pattern(37, 11, 5);  // odd width: rows padded to 64 bytes
    for (int k = 1; k < n; ++k) {
      EXPECT_FALSE(d.process(img.cview())) << "n " << n << " frame " << k;
      EXPECT_EQ(d.run(), k);
      EXPECT_FALSE(d.frozen());
    }
    EXPECT_TRUE(d.process(img.cview())) << "n " << n;
    EXPECT_EQ(d.run(), n);
    EXPECT_TRUE(d.frozen());
    EXPECT_EQ(d.detections(), 1u);
    // Reported once per run: still frozen, not reported again.
    for (int k = 0; k < 2 * n; ++k) EXPECT_FALSE(d.process(img.cview()));
    EXPECT_TRUE(d.frozen());
    EXPECT_EQ(d.run(), 3 * n);
    EXPECT_EQ(d.detections(), 1u);
    EXPECT_EQ(d.maxRun(), 3 * n);
  }
}

TEST(FrozenFrameDetector, OneChangedPixelResetsTheRun) {
  FrozenFrameDetector d = detector(4);
  ImageU8 img = pattern(64, 48, 1);
  for (int k = 0; k < 3; ++k) EXPECT_FALSE(d.process(img.cview()));
  EXPECT_EQ(d.run(), 3);
  img(63, 47) ^= 1;  // the very last byte compared
  EXPECT_FALSE(d.process(img.cview()));
  EXPECT_EQ(d.run(), 1);
  for (int k = 0; k < 2; ++k) EXPECT_FALSE(d.process(img.cview()));
  img(0, 0) ^= 0x80;  // the very first byte
  EXPECT_FALSE(d.process(img.cview()));
  EXPECT_EQ(d.run(), 1);
  EXPECT_EQ(d.maxRun(), 3);
  EXPECT_EQ(d.detections(), 0u);
  // Then frozen again after 3 more identical frames; a second run is a second detection.
  EXPECT_FALSE(d.process(img.cview()));
  EXPECT_FALSE(d.process(img.cview()));
  EXPECT_TRUE(d.process(img.cview()));
  img(10, 20) ^= 4;
  for (int k = 0; k < 3; ++k) EXPECT_FALSE(d.process(img.cview()));
  EXPECT_TRUE(d.process(img.cview()));
  EXPECT_EQ(d.detections(), 2u);
}

TEST(FrozenFrameDetector, ComparesPixelsNotPaddingAndHandlesSizeChanges) {
  FrozenFrameDetector d = detector(2);
  // Two views of the same pixels with different strides and different bytes in the padding.
  std::vector<std::uint8_t> a(10 * 4, 0), b(16 * 4, 0xAB);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x) a[y * 10 + x] = b[y * 16 + x] = static_cast<std::uint8_t>(x + y);
  EXPECT_FALSE(d.process(ImageView<const std::uint8_t>(a.data(), 8, 4, 10)));
  EXPECT_TRUE(d.process(ImageView<const std::uint8_t>(b.data(), 8, 4, 16)));
  // Same first bytes, other size: a new run.
  EXPECT_FALSE(d.process(ImageView<const std::uint8_t>(a.data(), 8, 3, 10)));
  EXPECT_EQ(d.run(), 1);
  d.reset();
  EXPECT_FALSE(d.process(ImageView<const std::uint8_t>(a.data(), 8, 3, 10)));
  EXPECT_EQ(d.run(), 1);
}

TEST(FrozenFrameDetector, OffDetectsNothing) {
  FrozenFrameDetector d = detector(0);
  const ImageU8 img = pattern(8, 8, 0);
  for (int k = 0; k < 100; ++k) EXPECT_FALSE(d.process(img.cview()));
  EXPECT_EQ(d.run(), 0);
  EXPECT_FALSE(d.frozen());
}

TEST(FrozenFrameDetector, BadParamsNameTheKey) {
  FrozenFrameParams p;
  EXPECT_TRUE(p.validate());
  EXPECT_EQ(p.frozen_frames, 30);
  for (int bad : {1, -1, 1000001}) {
    p.frozen_frames = bad;
    const Status s = p.validate();
    ASSERT_FALSE(s) << bad;
    EXPECT_EQ(s.message(),
              "frozen_frames must be 0 (off) or in [2, 1000000], got " + std::to_string(bad));
  }
  for (int good : {0, 2, 1000000}) {
    p.frozen_frames = good;
    EXPECT_TRUE(p.validate()) << good;
  }
}

}  // namespace
}  // namespace svslam

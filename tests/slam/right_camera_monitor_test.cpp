// RightCameraMonitor: missing, flat and frozen right images, a still scene, hysteresis.
#include "slam/right_camera_monitor.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace svslam {
namespace {

// A textured image whose content depends on `seed`.
ImageU8 textured(int seed, int w = 64, int h = 48) {
  ImageU8 im(w, h);
  std::uint32_t s = 2166136261u ^ static_cast<std::uint32_t>(seed);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      s = s * 16777619u + 12345u;
      im(x, y) = static_cast<std::uint8_t>(s >> 24);
    }
  return im;
}

TEST(RightCameraMonitor, LiveCameraIsUsable) {
  RightCameraMonitor m(RightCameraParams{});
  for (int k = 0; k < 5; ++k) {
    const ImageU8 l = textured(2 * k), r = textured(2 * k + 1);
    EXPECT_TRUE(m.process(l.cview(), r.cview()));
    EXPECT_EQ(m.state(), RightCameraState::kOk);
  }
  EXPECT_EQ(m.losses(), 0);
}

TEST(RightCameraMonitor, MissingFlatFrozenAndBack) {
  RightCameraParams p;
  p.resume_frames = 2;
  RightCameraMonitor m(p);
  int k = 0;
  const auto live = [&] {
    const ImageU8 l = textured(100 + k), r = textured(200 + k);
    ++k;
    return m.process(l.cview(), r.cview());
  };
  EXPECT_TRUE(live());
  // Missing: an empty view, then one of the wrong size.
  {
    const ImageU8 l = textured(1);
    EXPECT_FALSE(m.process(l.cview(), ImageView<const std::uint8_t>()));
    EXPECT_EQ(m.state(), RightCameraState::kMissing);
    const ImageU8 small = textured(2, 32, 24);
    EXPECT_FALSE(m.process(textured(3).cview(), small.cview()));
    EXPECT_EQ(m.state(), RightCameraState::kMissing);
  }
  // Two good frames to resume (hysteresis): the first is not yet usable.
  EXPECT_FALSE(live());
  EXPECT_EQ(m.state(), RightCameraState::kOk);
  EXPECT_TRUE(live());
  // Black.
  ImageU8 black(64, 48);
  black.fill(0);
  EXPECT_FALSE(m.process(textured(7).cview(), black.cview()));
  EXPECT_EQ(m.state(), RightCameraState::kFlat);
  EXPECT_FALSE(live());
  EXPECT_TRUE(live());
  // Frozen: the right image repeats while the left one changes.
  const ImageU8 stuck = textured(999);
  EXPECT_TRUE(m.process(textured(11).cview(), stuck.cview()));  // first sight: fine
  EXPECT_FALSE(m.process(textured(12).cview(), stuck.cview()));
  EXPECT_EQ(m.state(), RightCameraState::kFrozen);
  EXPECT_EQ(m.losses(), 3);
  EXPECT_EQ(m.unusableFrames(), 4);
}

TEST(RightCameraMonitor, StillSceneIsNotFrozen) {
  RightCameraMonitor m(RightCameraParams{});
  const ImageU8 l = textured(1), r = textured(2);
  for (int k = 0; k < 4; ++k) {
    EXPECT_TRUE(m.process(l.cview(), r.cview()));
    EXPECT_EQ(m.state(), RightCameraState::kOk);
  }
}

TEST(RightCameraMonitor, DisabledAcceptsAnything) {
  RightCameraParams p;
  p.enabled = false;
  RightCameraMonitor m(p);
  EXPECT_TRUE(m.process(textured(1).cview(), ImageView<const std::uint8_t>()));
}

TEST(RightCameraMonitor, BadParamsAreNamed) {
  RightCameraParams p;
  p.min_stddev = -1;
  EXPECT_NE(p.validate().message().find("min_stddev"), std::string::npos);
  p = RightCameraParams{};
  p.resume_frames = 0;
  EXPECT_NE(p.validate().message().find("resume_frames"), std::string::npos);
}

}  // namespace
}  // namespace svslam

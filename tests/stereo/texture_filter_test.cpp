// The texture filter's row functions against a brute-force window sum.
#include "stereo/texture_filter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <vector>

namespace svslam {
namespace {

TEST(TextureFilter, GradientSumsAddAndSubtractRows) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> u(0, 255);
  const int w = 37;
  std::vector<std::uint8_t> a(w + 2), b(w + 2);
  for (auto& v : a) v = static_cast<std::uint8_t>(u(rng));
  for (auto& v : b) v = static_cast<std::uint8_t>(u(rng));
  std::vector<std::uint32_t> sums(w, 5);
  addRowGradients(a.data() + 1, w, 1, sums.data());
  addRowGradients(b.data() + 1, w, 1, sums.data());
  for (int x = 0; x < w; ++x)
    EXPECT_EQ(sums[x], 5u + std::abs(a[x + 2] - a[x]) + std::abs(b[x + 2] - b[x])) << x;
  addRowGradients(a.data() + 1, w, -1, sums.data());
  for (int x = 0; x < w; ++x) EXPECT_EQ(sums[x], 5u + std::abs(b[x + 2] - b[x])) << x;
}

TEST(TextureFilter, LowTextureIsTheClampedWindowSumBelowTheLimit) {
  std::mt19937 rng(4);
  std::uniform_int_distribution<std::uint32_t> u(0, 40);
  for (int w : {1, 2, 5, 31, 64}) {
    for (int radius : {0, 1, 4, 9}) {
      std::vector<std::uint32_t> sums(static_cast<std::size_t>(w));
      for (auto& v : sums) v = u(rng);
      std::vector<std::uint8_t> low(static_cast<std::size_t>(w), 7);
      const double limit = 20.0 * (2 * radius + 1);
      markLowTexture(sums.data(), w, radius, limit, low.data());
      for (int x = 0; x < w; ++x) {
        double s = 0;
        for (int k = -radius; k <= radius; ++k) s += sums[std::clamp(x + k, 0, w - 1)];
        EXPECT_EQ(low[x], s < limit ? 1 : 0) << "w " << w << " radius " << radius << " x " << x;
      }
    }
  }
}

}  // namespace
}  // namespace svslam

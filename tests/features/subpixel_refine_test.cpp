// Gauss-Newton sub-pixel refinement, checked on images sampled from a continuous band-limited
// texture shifted by known sub-pixel amounts, beside the parabola through ZNCC scores that it
// replaces (whose pull towards integer shifts the test also measures, so the comparison can
// fail either way).
#include "features/subpixel_refine.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "features/patch_similarity.hpp"
#include "wave_texture.hpp"

namespace svslam {
namespace {

// Plane waves with wavelengths 3.2 .. 40 px (up to 2 rad/px: near-Nyquist content, where
// interpolation errors are largest), standard deviation 30 (rarely clipped).
struct WaveTexture : test_texture::WaveTexture {
  explicit WaveTexture(unsigned seed) : test_texture::WaveTexture(seed, 3.2, 40.0, 24, 30.0) {}
};

// image(x, y) = clamp(round(gain * tex(x + dx, y + dy) + offset)).
ImageU8 render(const WaveTexture& tex, int w, int h, double dx, double dy, double gain = 1.0,
               double offset = 0.0) {
  ImageU8 img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.view()(x, y) = static_cast<std::uint8_t>(
          std::clamp(std::lround(gain * tex(x + dx, y + dy) + offset), 0L, 255L));
  return img;
}

double parabola(double sm, double s0, double sp) {
  const double den = sm - 2 * s0 + sp;
  return den < 0 ? std::clamp(0.5 * (sm - sp) / den, -0.5, 0.5) : 0.0;
}

struct BiasStats {
  double worst_bias = 0;  // largest |mean error| over the fractions
  double rms = 0;
  int failed = 0;
};

// Disparities 17 + f, f = 0.05 .. 0.95: the right image is the left texture shifted, so the
// true disparity is known everywhere (L(x) = R(x - d)).
BiasStats disparityBias(bool refine, double gain = 1.0, double offset = 0.0) {
  BiasStats st;
  double sum_sq = 0;
  int n_all = 0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const WaveTexture tex(seed);
    const ImageU8 left = render(tex, 160, 48, 0, 0);
    for (int b = 0; b < 10; ++b) {
      const double d = 17.05 + 0.1 * b;
      const ImageU8 right = render(tex, 160, 48, d, 0, gain, offset);
      const int d0 = static_cast<int>(std::lround(d));
      double sum = 0;
      int n = 0;
      for (int y = 8; y < 40; y += 4)
        for (int x = 40; x < 150; x += 5) {
          double est = 0;
          if (refine) {
            // From the integer disparity (the worst start: the parabola's would be closer).
            if (!refineDisparity(left.cview(), right.cview(), x, y, 4, d0, SubpixelRefineParams{},
                                 est)) {
              ++st.failed;
              continue;
            }
          } else {
            const auto s = [&](int dd) {
              return zncc(left.cview(), x, y, right.cview(), x - dd, y, 4);
            };
            est = d0 + parabola(s(d0 - 1), s(d0), s(d0 + 1));
          }
          sum += est - d;
          sum_sq += (est - d) * (est - d);
          ++n;
          ++n_all;
        }
      if (n > 0) st.worst_bias = std::max(st.worst_bias, std::abs(sum / n));
    }
  }
  st.rms = std::sqrt(sum_sq / std::max(n_all, 1));
  return st;
}

TEST(SubpixelRefine, DisparityHasNoPullTowardsIntegers) {
  const BiasStats parab = disparityBias(false);
  const BiasStats ref = disparityBias(true);
  std::printf(
      "parabola: worst bias %.4f px, rms %.4f px; refined: worst bias %.4f px, rms %.4f px,"
      " %d failed\n",
      parab.worst_bias, parab.rms, ref.worst_bias, ref.rms, ref.failed);
  EXPECT_GT(parab.worst_bias, 0.015);  // the effect the refinement exists for
  EXPECT_LT(ref.worst_bias, 0.5 * parab.worst_bias);
  EXPECT_LT(ref.worst_bias, 0.012);
  EXPECT_LT(ref.rms, 0.5 * parab.rms);
  EXPECT_EQ(ref.failed, 0);
}

TEST(SubpixelRefine, DisparityIgnoresGainAndOffset) {
  const BiasStats ref = disparityBias(true, 0.7, 30.0);
  EXPECT_LT(ref.worst_bias, 0.015);
  EXPECT_LT(ref.rms, 0.03);
  EXPECT_EQ(ref.failed, 0);
}

TEST(SubpixelRefine, TranslationOfATemplate) {
  const WaveTexture tex(7);
  const int h = 5, side = 2 * h + 1;
  double worst = 0;
  for (double du : {-0.45, -0.2, 0.0, 0.15, 0.35})
    for (double dv : {-0.3, 0.1, 0.4}) {
      // The template centred on texture point (50.3, 40.7); the image holds that point at
      // integer (60, 30) shifted by (du, dv), gain 1.2 and offset -15.
      std::vector<std::uint8_t> tmpl(static_cast<std::size_t>(side * side));
      for (int j = -h; j <= h; ++j)
        for (int i = -h; i <= h; ++i)
          tmpl[static_cast<std::size_t>((j + h) * side + i + h)] =
              static_cast<std::uint8_t>(std::lround(tex(50.3 + i, 40.7 + j)));
      ImageU8 img(120, 64);
      for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 120; ++x)
          img.view()(x, y) = static_cast<std::uint8_t>(std::clamp(
              std::lround(1.2 * tex(50.3 + x - 60 - du, 40.7 + y - 30 - dv) - 15.0), 0L, 255L));
      double u = 0, v = 0;
      ASSERT_TRUE(
          refineTranslation(tmpl.data(), h, img.cview(), 60, 30, SubpixelRefineParams{}, u, v))
          << du << " " << dv;
      worst = std::max({worst, std::abs(u - (60 + du)), std::abs(v - (30 + dv))});
    }
  std::printf("template translation: worst error %.4f px\n", worst);
  EXPECT_LT(worst, 0.02);
}

TEST(SubpixelRefine, RefusesFlatPatchesBordersAndBadParams) {
  const ImageU8 flat = [] {
    ImageU8 im(64, 32);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 64; ++x) im.view()(x, y) = 90;
    return im;
  }();
  double d = -1, u = -1;
  EXPECT_FALSE(refineDisparity(flat.cview(), flat.cview(), 30, 16, 4, 5, {}, d));
  EXPECT_EQ(d, -1);  // outputs untouched on failure

  const WaveTexture tex(3);
  const ImageU8 img = render(tex, 64, 32, 0, 0);
  // Patch or its interpolation taps outside the image: refused, nothing read outside (ASan).
  EXPECT_FALSE(refineDisparity(img.cview(), img.cview(), 8, 16, 4, 3, {}, d));
  EXPECT_FALSE(refineDisparity(img.cview(), img.cview(), 60, 16, 4, 0, {}, d));
  EXPECT_FALSE(refineDisparity(img.cview(), img.cview(), 30, 2, 4, 0, {}, d));
  EXPECT_FALSE(refineDisparity(img.cview(), img.cview(), 30, 16, 4, std::nan(""), {}, d));
  EXPECT_EQ(d, -1);
  std::vector<std::uint8_t> tmpl(9 * 9, 100);
  for (std::size_t i = 0; i < tmpl.size(); ++i) tmpl[i] = static_cast<std::uint8_t>(i * 37 % 251);
  double v = -1;
  EXPECT_FALSE(refineTranslation(tmpl.data(), 4, img.cview(), 5, 16, {}, u, v));
  EXPECT_FALSE(refineTranslation(tmpl.data(), 4, img.cview(), 30, 28, {}, u, v));
  EXPECT_FALSE(refineTranslation(tmpl.data(), 1, img.cview(), 30, 16, {}, u, v));
  EXPECT_FALSE(refineTranslation(tmpl.data(), 4, img.cview(), std::nan(""), 16, {}, u, v));
  EXPECT_EQ(u, -1);

  SubpixelRefineParams p;
  EXPECT_TRUE(p.validate());
  p.max_iterations = 0;
  EXPECT_FALSE(p.validate());
  p = {};
  p.stop_px = std::nan("");
  EXPECT_FALSE(p.validate());
  p = {};
  p.max_shift_px = 5;
  EXPECT_FALSE(p.validate());
}

}  // namespace
}  // namespace svslam

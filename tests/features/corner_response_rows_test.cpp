// The streamed corner response against the definition: whole-image separable passes with
// replicated borders (computed here with the reference row kernel, image by image), for any
// stripe of rows, on odd sizes including images shorter than the filters' halo.
#include "features/corner_response_rows.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "simd/float_row_kernels.hpp"

namespace svslam {
namespace {

std::vector<float> kernel(int r, bool odd) {
  std::vector<float> k(static_cast<std::size_t>(2 * r + 1));
  for (int i = -r; i <= r; ++i)
    k[static_cast<std::size_t>(i + r)] =
        (odd ? -0.1f * static_cast<float>(i) : 1.0f) / static_cast<float>(1 + i * i);
  return k;
}

// out(x, y) = sum_j c[j] in(clamp(x - (j - r)), y)  (horizontal) or  in(x, clamp(y - (j - r))).
ImageF32 pass(const ImageF32& in, const std::vector<float>& c, bool horizontal) {
  const simd::FloatRowKernels& k = simd::floatRowKernels(simd::Backend::kScalar);
  const int w = in.width(), h = in.height(), r = static_cast<int>(c.size() / 2);
  ImageF32 out(w, h);
  std::vector<float> row(static_cast<std::size_t>(w));
  std::vector<std::vector<float>> shifted(c.size(), row);
  std::vector<const float*> taps(c.size());
  for (int y = 0; y < h; ++y) {
    for (std::size_t j = 0; j < c.size(); ++j) {
      const int d = static_cast<int>(j) - r;
      for (int x = 0; x < w; ++x)
        shifted[j][static_cast<std::size_t>(x)] =
            horizontal ? in(std::clamp(x - d, 0, w - 1), y) : in(x, std::clamp(y - d, 0, h - 1));
      taps[j] = shifted[j].data();
    }
    k.convolve(taps.data(), c.data(), static_cast<int>(c.size()), out.row(y), w);
  }
  return out;
}

ImageF32 expectedResponse(const ImageU8& img, const std::vector<float>& kd,
                          const std::vector<float>& kg, const std::vector<float>& ki, bool harris) {
  const simd::FloatRowKernels& k = simd::floatRowKernels(simd::Backend::kScalar);
  const int w = img.width(), h = img.height();
  ImageF32 f(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) f(x, y) = static_cast<float>(img(x, y));
  const ImageF32 ix = pass(pass(f, kd, true), kg, false), iy = pass(pass(f, kg, true), kd, false);
  ImageF32 xx(w, h), yy(w, h), xy(w, h), resp(w, h);
  for (int y = 0; y < h; ++y) k.products(ix.row(y), iy.row(y), xx.row(y), yy.row(y), xy.row(y), w);
  const ImageF32 mxx = pass(pass(xx, ki, true), ki, false), myy = pass(pass(yy, ki, true), ki, false),
                 mxy = pass(pass(xy, ki, true), ki, false);
  for (int y = 0; y < h; ++y)
    k.response(mxx.row(y), mxy.row(y), myy.row(y), harris, 0.04, resp.row(y), w, 0.0f);
  return resp;
}

ImageU8 texture(int w, int h) {
  ImageU8 img(w, h);
  std::uint32_t s = 777;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      s = s * 1664525u + 1013904223u;
      img(x, y) = static_cast<std::uint8_t>(
          std::clamp(120 + 70 * std::sin(0.3 * x) * std::cos(0.23 * y) + (s >> 27), 0.0, 255.0));
    }
  return img;
}

TEST(CornerResponseRows, AnyStripeEqualsTheWholeImagePasses) {
  const std::vector<float> kd = kernel(3, true), kg = kernel(3, false), ki = kernel(6, false);
  for (auto [w, h] : {std::pair{45, 37}, std::pair{70, 5}, std::pair{9, 1}}) {
    const ImageU8 img = texture(w, h);
    for (bool harris : {true, false}) {
      const ImageF32 want = expectedResponse(img, kd, kg, ki, harris);
      float want_max = 0;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) want_max = std::max(want_max, want(x, y));
      for (int stripes : {1, 2, 3, h}) {
        // One object reused over the stripes in reverse order: no row may come from a ring slot
        // left over from another stripe.
        CornerResponseRows rows(w, kd, kg, ki);
        ImageF32 got(w, h);
        float got_max = 0;
        for (int i = stripes - 1; i >= 0; --i)
          got_max = std::max(got_max, rows.process(img.cview(), harris, 0.04, h * i / stripes,
                                                   h * (i + 1) / stripes, got));
        for (int y = 0; y < h; ++y)
          ASSERT_EQ(std::memcmp(got.row(y), want.row(y), sizeof(float) * w), 0)
              << w << "x" << h << " row " << y << ", " << stripes << " stripes";
        EXPECT_EQ(got_max, want_max);
      }
    }
  }
}

}  // namespace
}  // namespace svslam

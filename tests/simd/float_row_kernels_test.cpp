// The corner detector's float row kernels: every backend this CPU runs gives the same bits as the
// portable reference, on odd lengths and unaligned starts; the reference computes the definition.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "simd/float_row_kernels.hpp"

namespace svslam::simd {
namespace {

std::vector<float> randomRow(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 50.0f);
  std::vector<float> v(static_cast<std::size_t>(n));
  for (float& x : v) x = g(rng);
  return v;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(FloatRowKernels, ReferenceComputesTheDefinition) {
  const FloatRowKernels& k = floatRowKernels(Backend::kScalar);
  const std::vector<float> t = randomRow(37, 1), p = randomRow(37, 2);
  std::vector<float> xx(37), yy(37), xy(37);
  k.products(t.data(), p.data(), xx.data(), yy.data(), xy.data(), 37);
  EXPECT_EQ(xx[5], t[5] * t[5]);
  EXPECT_EQ(yy[6], p[6] * p[6]);
  EXPECT_EQ(xy[7], t[7] * p[7]);
  // convolve: from zero, each product rounded, then added, in tap order.
  const std::vector<float> r0 = randomRow(37, 3), r1 = randomRow(37, 4), r2 = randomRow(37, 5);
  const float* rows[3] = {r0.data(), r1.data(), r2.data()};
  const float c[3] = {0.25f, -1.5f, 0.7f};
  std::vector<float> out(37);
  k.convolve(rows, c, 3, out.data(), 37);
  for (std::size_t x = 0; x < 37; ++x) {
    float expect = 0.0f;
    for (int j = 0; j < 3; ++j) {
      const volatile float prod = c[j] * rows[j][x];  // rounded, then added
      expect += prod;
    }
    EXPECT_EQ(out[x], expect) << x;
  }
  // response: the formulas, and the running maximum.
  const float a[2] = {4.0f, 1.0f}, b[2] = {1.0f, 0.0f}, cc[2] = {2.0f, 1.0f};
  float r[2];
  const float mh = k.response(a, b, cc, true, 0.04, r, 2, 0.0f);
  EXPECT_EQ(r[0], static_cast<float>(4.0 * 2.0 - 1.0 - 0.04 * 6.0 * 6.0));
  EXPECT_EQ(mh, std::max(r[0], r[1]));
  k.response(a, b, cc, false, 0.04, r, 2, 0.0f);
  EXPECT_EQ(r[0], static_cast<float>(3.0 - std::sqrt(1.0 + 1.0)));  // smaller eigenvalue
  EXPECT_EQ(r[1], 1.0f);
}

// Rows of few distinct values, so that ties between neighbours are common.
std::vector<float> coarseRow(int n, unsigned seed) {
  std::vector<float> v = randomRow(n, seed);
  for (float& x : v) x = std::round(x / 40.0f);
  return v;
}

// The 3x3 rule written out: r above thr and above every neighbour, ties to the first in raster
// order (a neighbour equal to r blocks it when it comes before, in the row above or to the left).
std::vector<int> maximaByDefinition(const std::vector<float>* rows, float thr, int x0, int x1) {
  std::vector<int> xs;
  for (int x = x0; x < x1; ++x) {
    const float r = rows[1][static_cast<std::size_t>(x)];
    bool keep = r > thr;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0) continue;
        const float q = rows[1 + dy][static_cast<std::size_t>(x + dx)];
        const bool before = dy < 0 || (dy == 0 && dx < 0);
        if (q > r || (before && q == r)) keep = false;
      }
    if (keep) xs.push_back(x);
  }
  return xs;
}

TEST(FloatRowKernels, LocalMaximaFollowTheRasterTieRule) {
  const FloatRowKernels& ref = floatRowKernels(Backend::kScalar);
  const int n = 301;
  const std::vector<float> rows[3] = {coarseRow(n, 7), coarseRow(n, 8), coarseRow(n, 9)};
  std::vector<int> xs(static_cast<std::size_t>(n));
  for (float thr : {-10.0f, 0.0f, 1.0f}) {
    const int c = ref.localMaxima(rows[0].data(), rows[1].data(), rows[2].data(), thr, 1, n - 1,
                                  xs.data());
    const std::vector<int> want = maximaByDefinition(rows, thr, 1, n - 1);
    ASSERT_GT(want.size(), 5u);
    EXPECT_EQ(std::vector<int>(xs.begin(), xs.begin() + c), want) << "thr " << thr;
  }
  // A plateau of equal values keeps exactly its first pixel in raster order.
  const std::vector<float> flat(12, 5.0f);
  const std::vector<float> plateau[3] = {flat, flat, flat};
  EXPECT_EQ(ref.localMaxima(plateau[0].data(), plateau[1].data(), plateau[2].data(), 0.0f, 1, 11,
                            xs.data()),
            0);  // every pixel has an equal neighbour before it
}

TEST(FloatRowKernels, EveryAvailableBackendIsBitExactWithTheReference) {
  int tested = 0;
  for (Backend b : {Backend::kAvx2, Backend::kAvx512, Backend::kNeon}) {
    if (!floatRowBackendAvailable(b)) continue;
    const FloatRowKernels& k = floatRowKernels(b);
    ASSERT_EQ(k.backend, b);
    ++tested;
    const FloatRowKernels& ref = floatRowKernels(Backend::kScalar);
    for (int n : {1, 7, 8, 9, 31, 64, 333, 1027})
      for (int off : {0, 1, 3}) {
        const std::vector<float> p = randomRow(n + off, static_cast<unsigned>(n + 11 * off));
        const std::vector<float> a = randomRow(n + off, static_cast<unsigned>(3 * n + off)),
                                 b2 = randomRow(n + off, static_cast<unsigned>(5 * n + off));
        std::vector<float> r[3], s[3];
        for (int i = 0; i < 3; ++i) r[i] = s[i] = std::vector<float>(static_cast<std::size_t>(n));
        ref.products(a.data() + off, p.data() + off, r[0].data(), r[1].data(), r[2].data(), n);
        k.products(a.data() + off, p.data() + off, s[0].data(), s[1].data(), s[2].data(), n);
        for (int i = 0; i < 3; ++i)
          ASSERT_TRUE(sameBits(r[i], s[i])) << k.name << " products, n = " << n;
        for (bool harris : {true, false}) {
          // Structure-tensor-like inputs: a, c >= 0; b of either sign.
          std::vector<float> ta(a), tc(p), ro1(static_cast<std::size_t>(n + off)), ro2(ro1);
          for (float& v : ta) v = v * v;
          for (float& v : tc) v = v * v;
          const float m1 = ref.response(ta.data() + off, b2.data() + off, tc.data() + off, harris,
                                        0.04, ro1.data() + off, n, 0.0f);
          const float m2 = k.response(ta.data() + off, b2.data() + off, tc.data() + off, harris,
                                      0.04, ro2.data() + off, n, 0.0f);
          ASSERT_TRUE(sameBits(ro1, ro2)) << k.name << " response, n = " << n;
          ASSERT_EQ(m1, m2) << k.name << " response maximum, n = " << n;
        }
        for (int taps : {1, 7, 13, 61}) {
          std::vector<std::vector<float>> src;
          std::vector<const float*> rows;
          std::vector<float> c;
          for (int j = 0; j < taps; ++j) {
            src.push_back(randomRow(n + off, static_cast<unsigned>(100 * j + n)));
            c.push_back(0.01f * static_cast<float>(j % 9) - 0.033f);
          }
          for (const auto& v : src) rows.push_back(v.data() + off);
          std::vector<float> o1(static_cast<std::size_t>(n)), o2(o1);
          ref.convolve(rows.data(), c.data(), taps, o1.data(), n);
          k.convolve(rows.data(), c.data(), taps, o2.data(), n);
          ASSERT_TRUE(sameBits(o1, o2)) << k.name << " convolve, n = " << n << ", taps " << taps;
        }
        if (n >= 3) {
          std::vector<float> m[3];
          for (int i = 0; i < 3; ++i) m[i] = coarseRow(n + off, static_cast<unsigned>(n * 3 + i));
          std::vector<int> x1(static_cast<std::size_t>(n)), x2(x1);
          for (int lo : {1, 2})
            for (float thr : {-1.0f, 0.0f}) {
              const int c1 = ref.localMaxima(m[0].data() + off, m[1].data() + off,
                                             m[2].data() + off, thr, lo, n - 1, x1.data());
              const int c2 = k.localMaxima(m[0].data() + off, m[1].data() + off,
                                           m[2].data() + off, thr, lo, n - 1, x2.data());
              ASSERT_EQ(c1, c2) << k.name << " localMaxima, n = " << n;
              ASSERT_TRUE(std::equal(x1.begin(), x1.begin() + c1, x2.begin()))
                  << k.name << " localMaxima, n = " << n;
            }
        }
      }
  }
  if (tested == 0) GTEST_SKIP() << "no SIMD float row backend runs on this CPU; reference only";
}

}  // namespace
}  // namespace svslam::simd

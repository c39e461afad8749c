// DenseStereo on synthetic pairs with known disparity, determinism across stripes, executors and
// SIMD backends, and bad arguments.
#include "stereo/dense_stereo.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <new>
#include <random>

#include "core/executor.hpp"

// Counts heap allocations made by this test binary (for the "allocates nothing once warm" test).
// GCC 12 flags the malloc/free pair behind a replaced operator new/delete once inlined
// (-Wmismatched-new-delete); the pairing is correct by construction.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
static std::atomic<long> g_allocations{0};
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace svslam {
namespace {

// Smooth random texture: sum of a few random sinusoids plus noise, values in [0, 255].
ImageU8 texture(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ImageU8 img(w, h);
  double fx[6], fy[6], ph[6];
  for (int k = 0; k < 6; ++k) {
    fx[k] = 0.05 + 0.6 * u(rng);
    fy[k] = 0.05 + 0.6 * u(rng);
    ph[k] = 6.28 * u(rng);
  }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double v = 128;
      for (int k = 0; k < 6; ++k) v += 18 * std::sin(fx[k] * x + fy[k] * y + ph[k]);
      v += 10 * (u(rng) - 0.5);
      img(x, y) = static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
    }
  return img;
}

// Right image of a fronto-parallel scene at disparity d (integer): R(x) = L(x + d).
ImageU8 shifted(const ImageU8& left, int d) {
  ImageU8 r(left.width(), left.height());
  for (int y = 0; y < left.height(); ++y)
    for (int x = 0; x < left.width(); ++x) r(x, y) = left(std::min(x + d, left.width() - 1), y);
  return r;
}

bool sameBits(const ImageF32& a, const ImageF32& b) {
  if (a.width() != b.width() || a.height() != b.height()) return false;
  for (int y = 0; y < a.height(); ++y)
    if (std::memcmp(a.row(y), b.row(y), sizeof(float) * static_cast<std::size_t>(a.width())) != 0)
      return false;
  return true;
}

class CountingExecutor final : public Executor {
 public:
  // Runs tasks in reverse order, to show the result does not depend on the order.
  void parallelFor(int n, TaskRef fn) override {
    for (int i = n - 1; i >= 0; --i) fn(i);
    calls += 1;
  }
  int concurrency() const override { return 4; }
  int calls = 0;
};

TEST(DenseStereo, RecoversConstantDisparityCensusAndSad) {
  const ImageU8 left = texture(160, 96, 1);
  const ImageU8 right = shifted(left, 11);
  for (MatchingCost c : {MatchingCost::kCensus, MatchingCost::kSad}) {
    DenseStereoParams p;
    p.cost = c;
    p.max_disp = 32;
    DenseStereo s(p, left.width(), left.height());
    ASSERT_TRUE(s.initStatus().isOk()) << s.initStatus().message();
    DisparityResult r;
    ASSERT_TRUE(s.process(left.cview(), right.cview(), r).isOk());
    int good = 0, valid = 0, interior = 0;
    for (int y = 0; y < left.height(); ++y)
      for (int x = 20; x < left.width() - 20; ++x) {
        ++interior;
        const float d = r.disparity_px(x, y);
        if (!std::isfinite(d)) continue;
        ++valid;
        EXPECT_TRUE(std::isfinite(r.sigma_d_px(x, y)));
        if (std::abs(d - 11.0f) < 0.5f) ++good;
      }
    EXPECT_GT(valid, interior * 95 / 100) << toString(c);
    EXPECT_GT(good, valid * 99 / 100) << toString(c);
    // No disparity can exist where x < d for the whole range: the leftmost columns.
    EXPECT_FALSE(std::isfinite(r.disparity_px(0, 10)));
  }
}

TEST(DenseStereo, SubpixelFollowsASlantedPlane) {
  // Right image sampled at x + d(x) with d(x) = 8 + x / 40 (linear interpolation of the left).
  const int w = 200, h = 64;
  const ImageU8 left = texture(w, h, 3);
  ImageU8 right(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      // Find the left position xl with xl - d(xl) = x: xl = (x + 8) / (1 - 1/40).
      const double xl = (x + 8.0) / (1.0 - 1.0 / 40.0);
      const int x0 = std::min(static_cast<int>(xl), w - 2);
      const double t = std::min(1.0, xl - x0);
      right(x, y) =
          static_cast<std::uint8_t>(std::lround((1 - t) * left(x0, y) + t * left(x0 + 1, y)));
    }
  DenseStereoParams p;
  p.max_disp = 24;
  DenseStereo s(p, w, h);
  DisparityResult r;
  ASSERT_TRUE(s.process(left.cview(), right.cview(), r).isOk());
  double sum_err_sub = 0, sum_err_int = 0;
  int n = 0;
  DenseStereoParams pi = p;
  pi.subpixel = false;
  DenseStereo si(pi, w, h);
  DisparityResult ri;
  ASSERT_TRUE(si.process(left.cview(), right.cview(), ri).isOk());
  for (int y = 5; y < h - 5; ++y)
    for (int x = 30; x < w - 30; ++x) {
      const double truth = 8.0 + x / 40.0;
      if (!std::isfinite(r.disparity_px(x, y)) || !std::isfinite(ri.disparity_px(x, y))) continue;
      sum_err_sub += std::abs(r.disparity_px(x, y) - truth);
      sum_err_int += std::abs(ri.disparity_px(x, y) - truth);
      ++n;
    }
  ASSERT_GT(n, 1000);
  EXPECT_LT(sum_err_sub / n, 0.25);
  EXPECT_LT(sum_err_sub, sum_err_int * 0.9);  // sub-pixel beats integer disparities
}

TEST(DenseStereo, IdenticalForAnyStripeCountExecutorAndBackend) {
  const ImageU8 left = texture(203, 77, 5);
  const ImageU8 right = shifted(left, 7);
  for (MatchingCost c : {MatchingCost::kCensus, MatchingCost::kSad}) {
    DenseStereoParams p;
    p.cost = c;
    p.max_disp = 40;
    p.texture_threshold = 2.0f;
    p.backend = simd::Backend::kScalar;
    DenseStereo ref(p, left.width(), left.height());
    DisparityResult r0;
    ASSERT_TRUE(ref.process(left.cview(), right.cview(), r0).isOk());
    for (simd::Backend b : {simd::Backend::kScalar, simd::Backend::kAvx2, simd::Backend::kAvx512,
                            simd::Backend::kNeon}) {
      if (!simd::backendAvailable(b)) continue;
      for (int stripes : {1, 3, 8, 77}) {
        DenseStereoParams q = p;
        q.backend = b;
        q.num_stripes = stripes;
        q.census_byte_planes = stripes % 2 == 0;  // both census layouts (words: AVX-512, NEON)
        DenseStereo s(q, left.width(), left.height());
        CountingExecutor ex;
        DisparityResult r;
        ASSERT_TRUE(s.process(left.cview(), right.cview(), r, ex).isOk());
        EXPECT_TRUE(sameBits(r0.disparity_px, r.disparity_px))
            << simd::backendName(b) << " stripes " << stripes;
        EXPECT_TRUE(sameBits(r0.sigma_d_px, r.sigma_d_px))
            << simd::backendName(b) << " stripes " << stripes;
        EXPECT_EQ(r0.stats.valid, r.stats.valid);
      }
    }
  }
}

TEST(DenseStereo, AllocatesNothingOnceWarm) {
  const ImageU8 left = texture(200, 100, 12);
  const ImageU8 right = shifted(left, 6);
  for (MatchingCost c : {MatchingCost::kCensus, MatchingCost::kSad}) {
    DenseStereoParams p;
    p.cost = c;
    p.prefilter = SadPrefilter::kMeanRemoval;
    p.max_disp = 24;
    p.num_stripes = 3;
    p.texture_threshold = 1.0f;
    DenseStereo s(p, 200, 100);
    DisparityResult r;
    SerialExecutor ex;
    ASSERT_TRUE(s.process(left.cview(), right.cview(), r, ex).isOk());  // warm: sizes the outputs
    const long before = g_allocations.load();
    ASSERT_TRUE(s.process(left.cview(), right.cview(), r, ex).isOk());
    EXPECT_EQ(g_allocations.load() - before, 0) << toString(c);
  }
}

TEST(DenseStereo, TinyImagesSmallerThanTheWindowsAreSafe) {
  // Windows larger than the image: borders are replicated, nothing is read out of bounds
  // (ASan in CI), every backend agrees with the scalar reference.
  for (int w : {9, 17, 40})
    for (int h : {1, 2, 5}) {
      const ImageU8 left = texture(w, h, 21);
      const ImageU8 right = shifted(left, 2);
      for (MatchingCost c : {MatchingCost::kCensus, MatchingCost::kSad}) {
        DenseStereoParams p;
        p.cost = c;
        p.max_disp = std::min(8, w - 1);
        p.window_w = 15;
        p.window_h = 15;
        p.backend = simd::Backend::kScalar;
        DenseStereo ref(p, w, h);
        ASSERT_TRUE(ref.initStatus().isOk()) << ref.initStatus().message();
        DisparityResult r0;
        ASSERT_TRUE(ref.process(left.cview(), right.cview(), r0).isOk());
        for (simd::Backend b :
             {simd::Backend::kAvx2, simd::Backend::kAvx512, simd::Backend::kNeon}) {
          if (!simd::backendAvailable(b)) continue;
          p.backend = b;
          p.num_stripes = h;
          DenseStereo s(p, w, h);
          DisparityResult r;
          ASSERT_TRUE(s.process(left.cview(), right.cview(), r).isOk());
          EXPECT_TRUE(sameBits(r0.disparity_px, r.disparity_px))
              << w << "x" << h << " " << simd::backendName(b);
        }
      }
    }
}

TEST(DenseStereo, RepeatedProcessGivesSameResult) {
  const ImageU8 left = texture(128, 64, 9);
  const ImageU8 right = shifted(left, 5);
  const ImageU8 other = texture(128, 64, 10);
  DenseStereoParams p;
  p.max_disp = 16;
  DenseStereo s(p, 128, 64);
  DisparityResult a, b, c;
  ASSERT_TRUE(s.process(left.cview(), right.cview(), a).isOk());
  ASSERT_TRUE(s.process(other.cview(), other.cview(), c).isOk());  // different content in between
  ASSERT_TRUE(s.process(left.cview(), right.cview(), b).isOk());
  EXPECT_TRUE(sameBits(a.disparity_px, b.disparity_px));
}

TEST(DenseStereo, FiltersRejectUntexturedAndInconsistentPixels) {
  ImageU8 flat(96, 48);
  flat.fill(100);
  DenseStereoParams p;
  p.max_disp = 16;
  p.texture_threshold = 1.0f;
  DenseStereo s(p, 96, 48);
  DisparityResult r;
  ASSERT_TRUE(s.process(flat.cview(), flat.cview(), r).isOk());
  EXPECT_EQ(r.stats.valid, 0);
  EXPECT_GT(r.stats.low_texture, 0);
  // Without the texture filter, a flat image is ambiguous everywhere: uniqueness rejects it.
  p.texture_threshold = 0.0f;
  DenseStereo s2(p, 96, 48);
  ASSERT_TRUE(s2.process(flat.cview(), flat.cview(), r).isOk());
  EXPECT_EQ(r.stats.valid, 0);
  EXPECT_GT(r.stats.not_unique, 0);
}

TEST(DenseStereo, RejectsBadParametersAndInputs) {
  DenseStereoParams p;
  EXPECT_TRUE(p.validate().isOk());
  // Each change alone makes the defaults invalid.
  using Change = std::function<void(DenseStereoParams&)>;
  const std::pair<const char*, Change> changes[] = {
      {"max_disp 0", [](DenseStereoParams& q) { q.max_disp = 0; }},
      {"min_disp -1", [](DenseStereoParams& q) { q.min_disp = -1; }},
      {"min_disp 64", [](DenseStereoParams& q) { q.min_disp = 64; }},
      {"census 9x9: 80 neighbours",
       [](DenseStereoParams& q) {
         q.census_w = 9;
         q.census_h = 9;
       }},
      {"census_w 4", [](DenseStereoParams& q) { q.census_w = 4; }},
      {"census 1x63: a side below 3",
       [](DenseStereoParams& q) {
         q.census_w = 1;
         q.census_h = 63;
       }},
      {"census 7x1", [](DenseStereoParams& q) { q.census_h = 1; }},
      {"window_w 33", [](DenseStereoParams& q) { q.window_w = 33; }},
      {"SAD 17x17 unfiltered: 289 * 255 overflows 16 bits",
       [](DenseStereoParams& q) {
         q.cost = MatchingCost::kSad;
         q.prefilter = SadPrefilter::kNone;
         q.window_w = 17;
         q.window_h = 17;
       }},
      {"texture_threshold NaN", [](DenseStereoParams& q) { q.texture_threshold = std::nanf(""); }},
      {"uniqueness_pct 101", [](DenseStereoParams& q) { q.uniqueness_pct = 101; }},
      {"num_stripes 0", [](DenseStereoParams& q) { q.num_stripes = 0; }},
      {"sigma_px[0] -1", [](DenseStereoParams& q) { q.sigma_model.sigma_px[0] = -1.0f; }},
  };
  for (const auto& [what, change] : changes) {
    DenseStereoParams q = p;
    change(q);
    EXPECT_FALSE(q.validate().isOk()) << what;
  }

  DenseStereoParams q;
  q.max_disp = 64;
  DenseStereo too_narrow(q, 64, 32);  // max_disp must be < width
  EXPECT_FALSE(too_narrow.initStatus().isOk());
  DisparityResult r;
  ImageU8 a(64, 32), b(64, 32);
  EXPECT_FALSE(too_narrow.process(a.cview(), b.cview(), r).isOk());

  DenseStereo s(p, 100, 50);
  ASSERT_TRUE(s.initStatus().isOk());
  ImageU8 l(100, 50), wrong(99, 50);
  EXPECT_EQ(s.process(l.cview(), wrong.cview(), r).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.process(ImageView<const std::uint8_t>(), l.cview(), r).code(),
            StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace svslam

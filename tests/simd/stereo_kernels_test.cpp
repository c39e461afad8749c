// Every SIMD backend available in this build and on this CPU against the scalar reference:
// exact equality on seeded random inputs with odd widths and strides. Inputs are allocated with
// exactly the readable ranges the header documents, so a sanitizer build catches over-reads;
// outputs are compared over whole buffers to catch stray writes.
#include "simd/stereo_kernels.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace svslam::simd {
namespace {

constexpr int kWidths[] = {1, 7, 31, 33, 65, 127, 641};
constexpr int kNumDisps[] = {1, 3, 16, 64, 65};
constexpr int kD0s[] = {0, 5};
constexpr int kShifts[] = {0, 1, 5, 16, 64, 69};  // d of the single-plane cost kernels

// Smallest odd stride of at least n + 2 (rows never start aligned to each other).
std::ptrdiff_t oddStride(int n) { return (n + 2) | 1; }

// How random values are drawn: kinds chosen so ties, the 0xFFFF marker and values on both sides
// of the int16 sign boundary all occur.
enum class Dist { kFull, kSmall, kSparseMax, kHigh };
constexpr Dist kDists[] = {Dist::kFull, Dist::kSmall, Dist::kSparseMax, Dist::kHigh};

std::uint16_t drawU16(std::mt19937& rng, Dist dist) {
  const std::uint32_t r = rng();
  switch (dist) {
    case Dist::kFull:
      return static_cast<std::uint16_t>(r);
    case Dist::kSmall:  // many ties
      return static_cast<std::uint16_t>(r % 4);
    case Dist::kSparseMax:  // mostly 0xFFFF, a few small values
      return (r % 8) == 0 ? static_cast<std::uint16_t>((r >> 8) % 6) : std::uint16_t{0xFFFF};
    case Dist::kHigh:  // around 0x8000 and at the top, ties included
      return static_cast<std::uint16_t>(((r % 2) ? 0x7FFE : 0xFFFC) + (r >> 8) % 4);
  }
  return 0;
}

std::uint8_t drawU8(std::mt19937& rng, Dist dist) {
  const std::uint32_t r = rng();
  switch (dist) {
    case Dist::kFull:
      return static_cast<std::uint8_t>(r);
    case Dist::kSmall:  // ties across 0x80
      return static_cast<std::uint8_t>(126 + r % 4);
    case Dist::kSparseMax:
      return (r % 2) ? std::uint8_t{0} : std::uint8_t{255};
    case Dist::kHigh:
      return static_cast<std::uint8_t>(250 + r % 6);
  }
  return 0;
}

std::uint64_t drawU64(std::mt19937_64& rng, Dist dist) {
  const std::uint64_t r = rng();
  switch (dist) {
    case Dist::kFull:
      return r;
    case Dist::kSmall:  // sparse bits
      return r & rng() & rng();
    case Dist::kSparseMax:
      return (r % 3) ? ~std::uint64_t{0} : 0;
    case Dist::kHigh:  // dense bits
      return r | rng() | rng();
  }
  return 0;
}

std::vector<std::uint16_t> randomU16(std::size_t n, std::mt19937& rng, Dist dist) {
  std::vector<std::uint16_t> v(n);
  for (auto& e : v) e = drawU16(rng, dist);
  return v;
}

std::vector<std::uint8_t> randomU8(std::size_t n, std::mt19937& rng, Dist dist) {
  std::vector<std::uint8_t> v(n);
  for (auto& e : v) e = drawU8(rng, dist);
  return v;
}

std::string where(const char* what, int width, int a, int b, int c, Dist dist) {
  return std::string(what) + " width=" + std::to_string(width) + " p1=" + std::to_string(a) +
         " p2=" + std::to_string(b) + " p3=" + std::to_string(c) +
         " dist=" + std::to_string(static_cast<int>(dist));
}

// Owning storage for a WtaRowState, exactly `width` entries per array.
struct WtaBuffers {
  explicit WtaBuffers(int width)
      : best(static_cast<std::size_t>(width)),
        second(best.size()),
        cm(best.size()),
        cp(best.size()),
        pm1(best.size()),
        pm2(best.size()),
        best_r(best.size()),
        bidx(best.size()),
        idx_r(best.size()) {}
  WtaRowState view() {
    return {best.data(), bidx.data(), second.data(), cm.data(),   cp.data(),
            pm1.data(),  pm2.data(),  best_r.data(), idx_r.data()};
  }
  std::vector<std::uint16_t> best, second, cm, cp, pm1, pm2, best_r;
  std::vector<std::int16_t> bidx, idx_r;
};

// "" when equal, else the first differing entry. cm and cp are not part of the streamed state
// backends must reproduce (wtaNeighbours sets them; tested below).
std::string firstDifference(const WtaBuffers& got, const WtaBuffers& want) {
  const auto cmp = [](const char* name, const auto& g, const auto& w) -> std::string {
    for (std::size_t x = 0; x < g.size(); ++x)
      if (g[x] != w[x])
        return std::string(name) + "[" + std::to_string(x) + "] = " + std::to_string(g[x]) +
               ", scalar " + std::to_string(w[x]);
    return "";
  };
  for (const std::string& d :
       {cmp("best", got.best, want.best), cmp("bidx", got.bidx, want.bidx),
        cmp("second", got.second, want.second), cmp("pm1", got.pm1, want.pm1),
        cmp("pm2", got.pm2, want.pm2),
        cmp("best_r", got.best_r, want.best_r), cmp("idx_r", got.idx_r, want.idx_r)})
    if (!d.empty()) return d;
  return "";
}

class StereoKernelsTest : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    if (!backendAvailable(GetParam()))
      GTEST_SKIP() << "backend " << backendName(GetParam())
                   << " not available in this build or on this CPU";
    k_ = &kernels(GetParam());
    ref_ = &scalarKernels();
    ASSERT_EQ(k_->backend, GetParam());
  }

  // Runs planes [i0, i0 + n) of `planes` (row r = plane r - 1, row 0 the plane before i0 = 0)
  // through both backends; the rows are copied into a buffer of exactly the readable rows.
  void wtaStep(const std::vector<std::uint16_t>& planes, std::ptrdiff_t stride, int i0, int n,
               int width, int d0, WtaBuffers& got, WtaBuffers& want, const std::string& ctx) {
    const std::size_t first = static_cast<std::size_t>(i0 * stride);
    const std::vector<std::uint16_t> rows(
        planes.begin() + static_cast<std::ptrdiff_t>(first),
        planes.begin() + static_cast<std::ptrdiff_t>(first + n * stride + width));
    k_->wtaUpdateRows(rows.data() + stride, stride, n, i0, width, d0, got.view());
    ref_->wtaUpdateRows(rows.data() + stride, stride, n, i0, width, d0, want.view());
    ASSERT_EQ(firstDifference(got, want), "")
        << ctx << " i0=" << i0 << " n_planes=" << n << " d0=" << d0;
  }

  const StereoKernels* k_ = nullptr;
  const StereoKernels* ref_ = nullptr;
};

TEST_P(StereoKernelsTest, TableIsComplete) {
  EXPECT_STREQ(k_->name, backendName(GetParam()));
  EXPECT_NE(k_->censusRow, nullptr);
  EXPECT_NE(k_->censusCostRow, nullptr);
  EXPECT_NE(k_->sadCostRow, nullptr);
  EXPECT_NE(k_->addSubRow, nullptr);
  EXPECT_NE(k_->boxRow, nullptr);
  EXPECT_NE(k_->wtaUpdateRows, nullptr);
  EXPECT_NE(k_->wtaNeighbours, nullptr);
  EXPECT_NE(k_->finalizeRow, nullptr);
}

TEST_P(StereoKernelsTest, CensusRowMatchesScalar) {
  // {win_w, win_h}: the usual windows, 64-bit full (13x5, 5x13), partial last byte planes and
  // degenerate ones.
  const int windows[][2] = {{3, 3},  {5, 5}, {7, 7}, {9, 7}, {7, 9}, {13, 5}, {5, 13},
                            {11, 5}, {9, 3}, {1, 1}, {3, 1}, {1, 3}, {1, 9}};
  std::mt19937 rng(12345);
  for (const auto& w : windows) {
    const int win_w = w[0];
    const int win_h = w[1];
    for (int width : kWidths) {
      for (Dist dist : kDists) {
        const std::ptrdiff_t stride = oddStride(width + win_w - 1);
        // Readable: rows [0, win_h), columns [0, width + win_w - 1) of each row.
        const auto img =
            randomU8(static_cast<std::size_t>((win_h - 1) * stride + width + win_w - 1), rng, dist);
        std::vector<std::uint64_t> got(static_cast<std::size_t>(width), 0xA5A5A5A5A5A5A5A5u);
        std::vector<std::uint64_t> want(static_cast<std::size_t>(width), 0x5A5A5A5A5A5A5A5Au);
        k_->censusRow(img.data(), stride, width, win_w, win_h, got.data());
        ref_->censusRow(img.data(), stride, width, win_w, win_h, want.data());
        ASSERT_EQ(got, want) << where("censusRow", width, win_w, win_h, 0, dist);
      }
    }
  }
}

// The byte-plane census pair (optional: skipped for backends without it). Planes against the
// scalar reference, and the scalar planes against the word layout (same census, same costs).
TEST_P(StereoKernelsTest, CensusPlanesMatchScalarAndTheWordLayout) {
  if (k_->censusPlanesRow == nullptr || k_->censusPlanesCostRows == nullptr)
    GTEST_SKIP() << "backend " << k_->name << " uses the word layout only";
  const int windows[][2] = {{3, 3}, {5, 5}, {7, 7}, {9, 7}, {7, 9}, {13, 5}, {11, 5}, {1, 9}};
  std::mt19937 rng(9876);
  for (const auto& w : windows) {
    const int win_w = w[0];
    const int win_h = w[1];
    const int n_planes = (win_w * win_h - 1 + 7) / 8;
    for (int width : kWidths) {
      for (Dist dist : kDists) {
        const std::ptrdiff_t stride = oddStride(width + win_w - 1);
        const auto img =
            randomU8(static_cast<std::size_t>((win_h - 1) * stride + width + win_w - 1), rng, dist);
        const auto img_r =
            randomU8(static_cast<std::size_t>((win_h - 1) * stride + width + win_w - 1), rng, dist);
        const std::ptrdiff_t ps = oddStride(width);  // plane stride
        const std::size_t n = static_cast<std::size_t>(7 * ps + width);
        std::vector<std::uint8_t> got(n, 0xA5), want(n, 0x5A), right(n, 0);
        k_->censusPlanesRow(img.data(), stride, width, win_w, win_h, got.data(), ps);
        ref_->censusPlanesRow(img.data(), stride, width, win_w, win_h, want.data(), ps);
        const std::string ctx = where("censusPlanesRow", width, win_w, win_h, 0, dist);
        std::vector<std::uint64_t> words(static_cast<std::size_t>(width));
        ref_->censusRow(img.data(), stride, width, win_w, win_h, words.data());
        for (int j = 0; j < 8; ++j) {
          for (int x = 0; x < width; ++x) {
            const std::size_t i = static_cast<std::size_t>(j * ps + x);
            ASSERT_EQ(got[i], want[i]) << ctx << " plane " << j << " x=" << x;
            ASSERT_EQ(want[i], static_cast<std::uint8_t>(words[static_cast<std::size_t>(x)] >>
                                                         (56 - 8 * j)))
                << ctx << " plane " << j << " x=" << x;
          }
        }
        // Costs: right planes readable at [-d, width - d) for d in [d_first, d_first + n_d).
        ref_->censusPlanesRow(img_r.data(), stride, width, win_w, win_h, right.data(), ps);
        std::vector<std::uint64_t> words_r(static_cast<std::size_t>(width));
        ref_->censusRow(img_r.data(), stride, width, win_w, win_h, words_r.data());
        for (int d_first : {0, 3}) {
          const int n_d = std::max(1, std::min(width - d_first, 17));
          if (d_first + n_d > width) continue;
          // Shift the right planes so index x - d stays inside [0, width) for every d.
          const int shift = d_first + n_d - 1;
          const int cw = width - shift;  // columns whose every candidate exists
          const std::ptrdiff_t cs = oddStride(cw);
          std::vector<std::uint8_t> cg(static_cast<std::size_t>(n_d * cs), 0xEE);
          std::vector<std::uint8_t> cr(cg.size(), 0x77);
          k_->censusPlanesCostRows(got.data() + shift, right.data() + shift, ps, n_planes, cw,
                                   d_first, n_d, cg.data(), cs);
          ref_->censusPlanesCostRows(want.data() + shift, right.data() + shift, ps, n_planes, cw,
                                     d_first, n_d, cr.data(), cs);
          for (int k = 0; k < n_d; ++k) {
            for (int x = 0; x < cw; ++x) {
              const std::size_t i = static_cast<std::size_t>(k * cs + x);
              ASSERT_EQ(cg[i], cr[i]) << ctx << " cost d=" << d_first + k << " x=" << x;
              const std::uint64_t lw = words[static_cast<std::size_t>(x + shift)];
              const std::uint64_t rw =
                  words_r[static_cast<std::size_t>(x + shift - d_first - k)];
              ASSERT_EQ(cr[i], __builtin_popcountll(lw ^ rw))
                  << ctx << " cost d=" << d_first + k << " x=" << x;
            }
          }
        }
      }
    }
  }
}

TEST_P(StereoKernelsTest, CensusCostRowMatchesScalar) {
  std::mt19937_64 rng(777);
  for (int width : kWidths) {
    for (int d : kShifts) {
      for (Dist dist : kDists) {
        // right is readable at [-d, width - d): a buffer of width words, passed at index d.
        std::vector<std::uint64_t> left(static_cast<std::size_t>(width));
        std::vector<std::uint64_t> right(static_cast<std::size_t>(width));
        for (auto& v : left) v = drawU64(rng, dist);
        for (auto& v : right) v = drawU64(rng, dist);
        std::vector<std::uint8_t> got(static_cast<std::size_t>(width), 0xEE);
        std::vector<std::uint8_t> want(static_cast<std::size_t>(width), 0x77);
        k_->censusCostRow(left.data(), right.data() + d, width, d, got.data());
        ref_->censusCostRow(left.data(), right.data() + d, width, d, want.data());
        ASSERT_EQ(got, want) << where("censusCostRow", width, d, 0, 0, dist);
      }
    }
  }
}

TEST_P(StereoKernelsTest, SadCostRowMatchesScalar) {
  std::mt19937 rng(4242);
  for (int width : kWidths) {
    for (int d : kShifts) {
      for (Dist dist : kDists) {
        const auto left = randomU8(static_cast<std::size_t>(width), rng, dist);
        const auto right = randomU8(static_cast<std::size_t>(width), rng,
                                    dist == Dist::kSmall ? Dist::kFull : dist);
        std::vector<std::uint8_t> got(static_cast<std::size_t>(width), 0xEE);
        std::vector<std::uint8_t> want(static_cast<std::size_t>(width), 0x77);
        k_->sadCostRow(left.data(), right.data() + d, width, d, got.data());
        ref_->sadCostRow(left.data(), right.data() + d, width, d, want.data());
        ASSERT_EQ(got, want) << where("sadCostRow", width, d, 0, 0, dist);
      }
    }
  }
}

TEST_P(StereoKernelsTest, AddSubRowMatchesScalar) {
  std::mt19937 rng(99);
  const std::size_t sizes[] = {0, 1, 7, 15, 16, 17, 31, 33, 63, 65, 127, 641, 641 * 65};
  for (std::size_t n : sizes) {
    for (Dist dist : kDists) {
      for (bool with_sub : {false, true}) {
        const auto acc0 = randomU16(n, rng, dist);  // wraps modulo 2^16 near 0 and 0xFFFF
        const auto add = randomU8(n, rng, Dist::kFull);
        const auto sub = randomU8(n, rng, dist);
        auto got = acc0;
        auto want = acc0;
        k_->addSubRow(got.data(), add.data(), with_sub ? sub.data() : nullptr, n);
        ref_->addSubRow(want.data(), add.data(), with_sub ? sub.data() : nullptr, n);
        ASSERT_EQ(got, want) << where("addSubRow", static_cast<int>(n), with_sub, 0, 0, dist);
      }
    }
  }
}

TEST_P(StereoKernelsTest, BoxRowMatchesScalar) {
  std::mt19937 rng(2024);
  for (int width : kWidths) {
    for (int win_w = 1; win_w <= 31; ++win_w) {
      for (Dist dist : kDists) {
        // Readable: in[0, width + win_w - 1).
        const auto in = randomU16(static_cast<std::size_t>(width + win_w - 1), rng, dist);
        std::vector<std::uint16_t> got(static_cast<std::size_t>(width), 0xBEEF);
        std::vector<std::uint16_t> want(static_cast<std::size_t>(width), 0xCAFE);
        k_->boxRow(in.data(), width, win_w, got.data());
        ref_->boxRow(in.data(), width, win_w, want.data());
        ASSERT_EQ(got, want) << where("boxRow", width, win_w, 0, 0, dist);
      }
    }
  }
}

// num_disp aggregated planes at an odd stride, preceded by the 0xFFFF row of plane -1. A few
// columns are forced all-0xFFFF or all-equal (ties on every plane) whatever the distribution.
std::vector<std::uint16_t> randomPlanes(int width, int num_disp, std::ptrdiff_t stride,
                                        std::mt19937& rng, Dist dist) {
  auto c = randomU16(static_cast<std::size_t>(num_disp * stride + width), rng, dist);
  std::fill(c.begin(), c.begin() + stride, std::uint16_t{0xFFFF});
  for (int x = 0; x < width; x += 5) {
    const std::uint16_t v = (x % 10 == 0) ? std::uint16_t{0xFFFF} : drawU16(rng, dist);
    for (int i = 0; i < num_disp; ++i) c[static_cast<std::size_t>((i + 1) * stride + x)] = v;
  }
  return c;
}

// A whole row as the dense stage runs it: wtaInitRow, then every plane in blocks of varying
// size; the state is compared after every block.
TEST_P(StereoKernelsTest, WtaUpdateRowsMatchesScalarOverWholeRows) {
  std::mt19937 rng(31337);
  const int schedules[][4] = {{1000, 0, 0, 0}, {1, 1, 1, 1}, {3, 7, 1, 16}, {16, 5, 2, 9}};
  for (int width : kWidths) {
    for (int num_disp : kNumDisps) {
      for (int d0 : {0, 5, width}) {
        for (Dist dist : kDists) {
          for (const auto& sched : schedules) {
            const std::ptrdiff_t stride = oddStride(width);
            const auto planes = randomPlanes(width, num_disp, stride, rng, dist);
            WtaBuffers got(width), want(width);
            wtaInitRow(got.view(), width);
            wtaInitRow(want.view(), width);
            int step = 0;
            for (int i0 = 0; i0 < num_disp;) {
              const int n = std::min(num_disp - i0, std::max(sched[step++ % 4], 1));
              wtaStep(planes, stride, i0, n, width, d0, got, want,
                      where("wtaUpdateRows", width, num_disp, d0, sched[1], dist));
              if (HasFatalFailure()) return;
              i0 += n;
            }
          }
        }
      }
    }
  }
}

// Arbitrary states and i0 > 0: every branch of the reference from any starting point, bidx at
// i0 - 1 often (the "right neighbour" branch) and -1 often.
TEST_P(StereoKernelsTest, WtaUpdateRowsMatchesScalarFromAnyState) {
  std::mt19937 rng(5150);
  for (int width : kWidths) {
    for (int i0 : {1, 5, 40}) {
      for (int n : {1, 2, 3, 16}) {
        for (Dist dist : kDists) {
          for (int d0 : kD0s) {
            const std::ptrdiff_t stride = oddStride(width);
            auto planes = randomPlanes(width, i0 + n, stride, rng, dist);
            for (int x = 0; x < width; ++x)  // plane i0 - 1, the `prev` row of the first plane
              planes[static_cast<std::size_t>(i0 * stride + x)] = drawU16(rng, dist);
            WtaBuffers got(width);
            for (auto* v :
                 {&got.best, &got.second, &got.cm, &got.cp, &got.pm1, &got.pm2, &got.best_r})
              for (auto& e : *v) e = drawU16(rng, dist);
            for (auto* v : {&got.bidx, &got.idx_r}) {
              for (auto& e : *v) {
                const std::uint32_t r = rng() % 4;
                e = static_cast<std::int16_t>(r == 0   ? -1
                                              : r == 1 ? i0 - 1
                                                       : static_cast<int>(rng() % (i0 + n)));
              }
            }
            WtaBuffers want = got;
            wtaStep(planes, stride, i0, n, width, d0, got, want,
                    where("wtaUpdateRows any state", width, i0, n, d0, dist));
            if (HasFatalFailure()) return;
          }
        }
      }
    }
  }
}

// finalizeRow against the scalar reference: random final WTA states (no candidate, ties,
// 0xFFFF markers, flat and negative parabolas), every filter switched on and off, a texture
// mask or none; outputs compared bit for bit (float bits), counts exactly.
TEST_P(StereoKernelsTest, FinalizeRowMatchesScalar) {
  std::mt19937 rng(4242);
  std::vector<float> sigma_table(301);
  for (auto& v : sigma_table) v = static_cast<float>(rng() % 1000) / 997.0f;
  for (int width : kWidths) {
    for (int num_disp : {1, 3, 16, 64}) {
      for (int d0 : kD0s) {
        for (int variant = 0; variant < 16; ++variant) {
          FinalizeParams p{};
          p.num_disp = num_disp;
          p.d0 = d0;
          p.uniqueness_pct = (variant & 1) ? 10 : 0;
          p.lr_check = (variant & 2) != 0;
          p.lr_max_diff = (variant & 4) ? 1 : 0;
          p.subpixel = (variant & 8) != 0;
          p.inv_area = 1.0f / 81.0f;
          p.sigma_by_denom = sigma_table.data();
          p.max_denom = static_cast<int>(sigma_table.size()) - 1;
          WtaBuffers st(width);
          st.idx_r.resize(static_cast<std::size_t>(width) + 1);  // readable at [0, width + 1)
          const auto draw_idx = [&]() {
            const std::uint32_t r = rng() % 8;
            return static_cast<std::int16_t>(r == 0 ? -1 : static_cast<int>(rng() % num_disp));
          };
          for (int x = 0; x < width; ++x) {
            const std::size_t ux = static_cast<std::size_t>(x);
            st.bidx[ux] = draw_idx();
            st.best[ux] = static_cast<std::uint16_t>(rng() % 200);
            const std::uint32_t r = rng();
            st.second[ux] = (r % 7 == 0) ? std::uint16_t{0xFFFF}
                                         : static_cast<std::uint16_t>(st.best[ux] + r % 40);
            st.cm[ux] = (r % 5 == 0) ? std::uint16_t{0xFFFF}
                                     : static_cast<std::uint16_t>(st.best[ux] + (r >> 8) % 200);
            st.cp[ux] = (r % 11 == 0) ? std::uint16_t{0xFFFF}
                                      : static_cast<std::uint16_t>(rng() % 400);
          }
          for (auto& e : st.idx_r) e = draw_idx();
          std::vector<std::uint8_t> tex(static_cast<std::size_t>(width));
          for (auto& e : tex) e = static_cast<std::uint8_t>(rng() % 5 == 0);
          const std::uint8_t* low = (variant % 3 == 0) ? tex.data() : nullptr;
          const std::size_t n = static_cast<std::size_t>(width);
          std::vector<float> gd(n), gs(n), gc(n), wd(n), ws(n), wc(n);
          FinalizeCounts gcnt, wcnt;
          gcnt.valid = wcnt.valid = 7;  // counts are incremented, not reset
          k_->finalizeRow(st.view(), low, width, p, gd.data(), gs.data(), gc.data(), gcnt);
          ref_->finalizeRow(st.view(), low, width, p, wd.data(), ws.data(), wc.data(), wcnt);
          const std::string ctx = where("finalizeRow", width, num_disp, d0, variant, Dist::kFull);
          for (std::size_t x = 0; x < n; ++x) {
            ASSERT_EQ(std::memcmp(&gd[x], &wd[x], sizeof(float)), 0)
                << ctx << " disp x=" << x << " " << gd[x] << " vs " << wd[x];
            ASSERT_EQ(std::memcmp(&gs[x], &ws[x], sizeof(float)), 0) << ctx << " sigma x=" << x;
            ASSERT_EQ(std::memcmp(&gc[x], &wc[x], sizeof(float)), 0) << ctx << " curv x=" << x;
          }
          EXPECT_EQ(gcnt.no_candidate, wcnt.no_candidate) << ctx;
          EXPECT_EQ(gcnt.low_texture, wcnt.low_texture) << ctx;
          EXPECT_EQ(gcnt.not_unique, wcnt.not_unique) << ctx;
          EXPECT_EQ(gcnt.lr_inconsistent, wcnt.lr_inconsistent) << ctx;
          EXPECT_EQ(gcnt.valid, wcnt.valid) << ctx;
          EXPECT_EQ(wcnt.no_candidate + wcnt.low_texture + wcnt.not_unique +
                        wcnt.lr_inconsistent + wcnt.valid,
                    width + 7)
              << ctx;
        }
      }
    }
  }
}

// wtaNeighbours against the scalar reference: random planes (some 0xFFFF), bidx anywhere in
// [-1, num_disp), rows allocated with exactly the documented readable range.
TEST_P(StereoKernelsTest, WtaNeighboursMatchesScalar) {
  std::mt19937 rng(8080);
  for (int width : kWidths) {
    for (int num_disp : {1, 2, 3, 16, 65}) {
      for (Dist dist : kDists) {
        const std::ptrdiff_t stride = oddStride(width);
        std::vector<std::uint16_t> planes(
            static_cast<std::size_t>((num_disp - 1) * stride + width + 1));
        for (auto& v : planes) v = drawU16(rng, dist);
        WtaBuffers got(width);
        for (auto& b : got.bidx) b = static_cast<std::int16_t>(static_cast<int>(rng() % (num_disp + 1)) - 1);
        for (auto* v : {&got.cm, &got.cp})
          for (auto& e : *v) e = drawU16(rng, Dist::kFull);
        WtaBuffers want = got;
        k_->wtaNeighbours(planes.data(), stride, num_disp, width, got.view());
        ref_->wtaNeighbours(planes.data(), stride, num_disp, width, want.view());
        ASSERT_EQ(got.cm, want.cm) << where("wtaNeighbours cm", width, num_disp, 0, 0, dist);
        ASSERT_EQ(got.cp, want.cp) << where("wtaNeighbours cp", width, num_disp, 0, 0, dist);
      }
    }
  }
}

// wtaInitRow is shared by all backends; checked here once per backend run for simplicity.
TEST_P(StereoKernelsTest, WtaInitRowSetsTheDocumentedStart) {
  WtaBuffers b(33);
  for (auto* v : {&b.best, &b.second, &b.cm, &b.cp, &b.pm1, &b.pm2, &b.best_r})
    std::fill(v->begin(), v->end(), std::uint16_t{3});
  std::fill(b.bidx.begin(), b.bidx.end(), std::int16_t{3});
  std::fill(b.idx_r.begin(), b.idx_r.end(), std::int16_t{3});
  wtaInitRow(b.view(), 33);
  for (auto* v : {&b.best, &b.second, &b.cm, &b.cp, &b.pm1, &b.pm2, &b.best_r})
    EXPECT_EQ(*v, std::vector<std::uint16_t>(33, 0xFFFF));
  EXPECT_EQ(b.bidx, std::vector<std::int16_t>(33, -1));
  EXPECT_EQ(b.idx_r, std::vector<std::int16_t>(33, -1));
}

// The scalar reference itself against the meaning WtaRowState documents, computed directly
// from all planes at once (the streaming form must not drift from it).
TEST(ScalarReference, WtaUpdateRowsMeansWhatWtaRowStateDocuments) {
  std::mt19937 rng(2718);
  for (int width : {1, 7, 33, 127}) {
    for (int num_disp : kNumDisps) {
      for (int d0 : kD0s) {
        for (Dist dist : kDists) {
          const std::ptrdiff_t stride = oddStride(width);
          const auto planes = randomPlanes(width, num_disp, stride, rng, dist);
          const auto agg = [&](int i, int x) {
            return planes[static_cast<std::size_t>((i + 1) * stride + x)];
          };
          WtaBuffers s(width);
          wtaInitRow(s.view(), width);
          scalarKernels().wtaUpdateRows(planes.data() + stride, stride, num_disp, 0, width, d0,
                                        s.view());
          const std::string ctx = where("definition", width, num_disp, d0, 0, dist);
          for (int x = 0; x < width; ++x) {
            std::uint16_t best = 0xFFFF;
            int bidx = -1;
            for (int i = 0; i < num_disp; ++i) {
              if (agg(i, x) < best) {
                best = agg(i, x);
                bidx = i;
              }
            }
            std::uint16_t second = 0xFFFF;
            for (int i = 0; i < num_disp; ++i)
              if (std::abs(i - bidx) > 1) second = std::min(second, agg(i, x));
            const std::uint16_t cm = bidx >= 1 ? agg(bidx - 1, x) : std::uint16_t{0xFFFF};
            const std::uint16_t cp =
                bidx >= 0 && bidx + 1 < num_disp ? agg(bidx + 1, x) : std::uint16_t{0xFFFF};
            ASSERT_EQ(s.best[static_cast<std::size_t>(x)], best) << ctx << " x=" << x;
            ASSERT_EQ(s.bidx[static_cast<std::size_t>(x)], bidx) << ctx << " x=" << x;
            ASSERT_EQ(s.second[static_cast<std::size_t>(x)], second) << ctx << " x=" << x;
            ASSERT_EQ(s.cm[static_cast<std::size_t>(x)], cm) << ctx << " x=" << x;
            ASSERT_EQ(s.cp[static_cast<std::size_t>(x)], cp) << ctx << " x=" << x;
            WtaBuffers n = s;  // the stored-plane form gives the same neighbours
            n.cm.assign(n.cm.size(), 0x1234);
            n.cp.assign(n.cp.size(), 0x1234);
            wtaNeighboursRange(planes.data() + stride, stride, num_disp, x, x + 1, n.view());
            ASSERT_EQ(n.cm[static_cast<std::size_t>(x)], cm) << ctx << " x=" << x;
            ASSERT_EQ(n.cp[static_cast<std::size_t>(x)], cp) << ctx << " x=" << x;
            std::uint16_t best_r = 0xFFFF;
            int idx_r = -1;
            for (int i = 0; i < num_disp && x + d0 + i < width; ++i) {
              if (agg(i, x + d0 + i) < best_r) {
                best_r = agg(i, x + d0 + i);
                idx_r = i;
              }
            }
            ASSERT_EQ(s.best_r[static_cast<std::size_t>(x)], best_r) << ctx << " xr=" << x;
            ASSERT_EQ(s.idx_r[static_cast<std::size_t>(x)], idx_r) << ctx << " xr=" << x;
          }
        }
      }
    }
  }
}

std::string paramName(const ::testing::TestParamInfo<Backend>& info) {
  return backendName(info.param);
}

INSTANTIATE_TEST_SUITE_P(Backends, StereoKernelsTest,
                         ::testing::Values(Backend::kScalar, Backend::kAvx2, Backend::kAvx512,
                                           Backend::kNeon),
                         paramName);

class BackendSelectTest : public ::testing::TestWithParam<Backend> {};

TEST_P(BackendSelectTest, KernelsOfAnAvailableBackend) {
  const Backend b = GetParam();
  if (b == Backend::kAuto) {
    const Backend best = bestBackend();
    EXPECT_NE(best, Backend::kAuto);
    EXPECT_TRUE(backendAvailable(best));
    EXPECT_EQ(kernels(Backend::kAuto).backend, best);
    std::string available;
    for (Backend c : {Backend::kScalar, Backend::kAvx2, Backend::kAvx512, Backend::kNeon})
      if (backendAvailable(c)) available += std::string(" ") + backendName(c);
    std::printf("available backends:%s; auto -> %s\n", available.c_str(), backendName(best));
    return;
  }
  if (!backendAvailable(b)) GTEST_SKIP() << "backend " << backendName(b) << " not available";
  EXPECT_EQ(kernels(b).backend, b);
  EXPECT_STREQ(kernels(b).name, backendName(b));
}

TEST_P(BackendSelectTest, ParseAndNameRoundTrip) {
  Backend parsed = GetParam() == Backend::kScalar ? Backend::kAuto : Backend::kScalar;
  ASSERT_TRUE(parseBackend(backendName(GetParam()), parsed)) << backendName(GetParam());
  EXPECT_EQ(parsed, GetParam());
}

TEST_P(BackendSelectTest, ParseRejectsOtherNames) {
  const std::string name = backendName(GetParam());
  Backend out = GetParam();
  EXPECT_FALSE(parseBackend("", out));
  EXPECT_FALSE(parseBackend((name + " ").c_str(), out));
  EXPECT_FALSE(parseBackend(name.substr(0, name.size() - 1).c_str(), out));
  std::string upper = name;
  for (char& ch : upper) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  EXPECT_FALSE(parseBackend(upper.c_str(), out));
  EXPECT_EQ(out, GetParam());  // untouched on failure
}

INSTANTIATE_TEST_SUITE_P(Backends, BackendSelectTest,
                         ::testing::Values(Backend::kAuto, Backend::kScalar, Backend::kAvx2,
                                           Backend::kAvx512, Backend::kNeon),
                         paramName);

}  // namespace
}  // namespace svslam::simd

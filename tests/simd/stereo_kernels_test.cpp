// Every SIMD backend available in this build and on this CPU against the scalar reference:
// exact equality on seeded random inputs with odd widths and strides. Inputs are allocated with
// exactly the readable ranges the header documents, so a sanitizer build catches over-reads;
// outputs are compared over whole buffers to catch stray writes.
// This file: census, SAD, running sums and box; stereo_kernels_wta_test.cpp: winner-take-all
// and finalizeRow; backend_select_test.cpp: the run-time choice.
#include <gtest/gtest.h>

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


#include "simd/stereo_kernels.hpp"
#include "stereo_kernels_test_support.hpp"

namespace svslam::simd {
namespace {

using namespace test_support;

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
  std::vector<int> widths(std::begin(kWidths), std::end(kWidths));
  widths.insert(widths.end(), {1030, 2053});  // rows longer than a backend's chunk of work
  for (int width : widths) {
    for (int win_w = 1; win_w <= 36; ++win_w) {
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

INSTANTIATE_TEST_SUITE_P(Backends, StereoKernelsTest,
                         ::testing::Values(Backend::kScalar, Backend::kAvx2, Backend::kAvx512,
                                           Backend::kNeon),
                         paramName);

}  // namespace
}  // namespace svslam::simd

#pragma once
// Shared by the stereo kernel tests (one executable, simd_stereo_kernels_test): seeded random
// inputs whose kinds make ties, the 0xFFFF marker and int16 sign boundaries occur, the WTA row
// state buffers, and the fixture that runs a backend beside the scalar reference.
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

namespace svslam::simd::test_support {

constexpr int kWidths[] = {1, 7, 31, 33, 65, 127, 641};
constexpr int kNumDisps[] = {1, 3, 16, 64, 65};
constexpr int kD0s[] = {0, 5};
constexpr int kShifts[] = {0, 1, 5, 16, 64, 69};  // d of the single-plane cost kernels

// Smallest odd stride of at least n + 2 (rows never start aligned to each other).
inline std::ptrdiff_t oddStride(int n) { return (n + 2) | 1; }

// How random values are drawn: kinds chosen so ties, the 0xFFFF marker and values on both sides
// of the int16 sign boundary all occur.
enum class Dist { kFull, kSmall, kSparseMax, kHigh };
constexpr Dist kDists[] = {Dist::kFull, Dist::kSmall, Dist::kSparseMax, Dist::kHigh};

inline std::uint16_t drawU16(std::mt19937& rng, Dist dist) {
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

inline std::uint8_t drawU8(std::mt19937& rng, Dist dist) {
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

inline std::uint64_t drawU64(std::mt19937_64& rng, Dist dist) {
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

inline std::vector<std::uint16_t> randomU16(std::size_t n, std::mt19937& rng, Dist dist) {
  std::vector<std::uint16_t> v(n);
  for (auto& e : v) e = drawU16(rng, dist);
  return v;
}

inline std::vector<std::uint8_t> randomU8(std::size_t n, std::mt19937& rng, Dist dist) {
  std::vector<std::uint8_t> v(n);
  for (auto& e : v) e = drawU8(rng, dist);
  return v;
}

inline std::string where(const char* what, int width, int a, int b, int c, Dist dist) {
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
inline std::string firstDifference(const WtaBuffers& got, const WtaBuffers& want) {
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

inline std::string paramName(const ::testing::TestParamInfo<Backend>& info) {
  return backendName(info.param);
}

}  // namespace svslam::simd::test_support

#pragma once
// FAST segment tests (Rosten & Drummond 2006) on 8-bit images. Header-only so the per-pixel
// tests inline into the detector loops of orb_extractor.cpp.
//
// FAST 9-16: the 16 pixels x_0..x_15 of the Bresenham circle of radius 3 around p (offsets in
// kFastCircle16, the same order as OpenCV's). p is a corner at threshold t (grey levels) when
// 9 contiguous circle pixels are all brighter, x_i > I(p) + t, or all darker, x_i < I(p) - t.
// FAST 5-8: the 8 pixels of the radius-1 ring (kFastCircle8), 5 contiguous ones.
//
// Score (OpenCV's FAST response): the largest t for which p is still a corner,
//   score = max over arcs A of N/2+1 contiguous circle pixels of
//           max(min_{i in A} (x_i - I(p)), min_{i in A} (I(p) - x_i)) - 1,
// clamped to 0..254. So p is a corner at threshold t >= 1 exactly when score >= t, and a pixel
// that is not a corner at t has score < t. The score is defined for every pixel whose circle
// lies inside the image.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/image.hpp"

namespace svslam {

enum class FastMask { k9of16, k5of8 };

// Circle offsets (dx, dy), contiguous order.
inline constexpr int kFastCircle16[16][2] = {
    {0, 3},  {1, 3},   {2, 2},   {3, 1},   {3, 0},  {3, -1}, {2, -2}, {1, -3},
    {0, -3}, {-1, -3}, {-2, -2}, {-3, -1}, {-3, 0}, {-3, 1}, {-2, 2}, {-1, 3}};
inline constexpr int kFastCircle8[8][2] = {{0, 1},  {1, 1},   {1, 0},  {1, -1},
                                           {0, -1}, {-1, -1}, {-1, 0}, {-1, 1}};

// Circle radius in pixels: a score needs radius <= x < width - radius (same for y).
constexpr int fastRadius(FastMask m) { return m == FastMask::k9of16 ? 3 : 1; }

namespace fast_detail {

// max(1, max over arcs of max(min(x_i - p), min(p - x_i))) - 1: the windows starting at k and
// k + 1 share the N/2 pixels k + 1 .. k + N/2, so they are taken in pairs, and a pair whose first
// three shared differences cannot beat the best so far is skipped (the scheme of OpenCV's
// cornerScore, which gives the same values).
template <int N>
int score(const std::uint8_t* p, const std::array<std::ptrdiff_t, N>& offsets) {
  constexpr int kH = N / 2;
  const int v = p[0];
  int d[N + kH + 1];  // I(p) - x_i, circularly extended
  for (int i = 0; i < N; ++i) d[i] = v - p[offsets[static_cast<std::size_t>(i)]];
  for (int i = N; i < N + kH + 1; ++i) d[i] = d[i - N];
  int a0 = 1;  // darker arcs: best min(p - x_i)
  for (int k = 0; k < N; k += 2) {
    int a = std::min(std::min(d[k + 1], d[k + 2]), d[k + 3]);
    if (a <= a0) continue;
    for (int i = 4; i <= kH; ++i) a = std::min(a, d[k + i]);
    a0 = std::max(a0, std::max(std::min(a, d[k]), std::min(a, d[k + kH + 1])));
  }
  int b0 = -a0;  // brighter arcs, negated: min over arcs of max(p - x_i)
  for (int k = 0; k < N; k += 2) {
    int b = std::max(std::max(d[k + 1], d[k + 2]), d[k + 3]);
    if (b >= b0) continue;
    for (int i = 4; i <= kH; ++i) b = std::max(b, d[k + i]);
    b0 = std::min(b0, std::min(std::max(b, d[k]), std::max(b, d[k + kH + 1])));
  }
  return std::min(-b0 - 1, 254);
}

// The same score without branches: the minimum and maximum of d over each window of N/2 + 1
// contiguous pixels, lane by lane in fixed-size loops of 16-bit integers that the compiler
// vectorises (SSE2 / NEON baselines; integer min and max, so the values are exactly score()'s:
// fast_detector_test compares the two on every pixel of random and rendered images).
template <int N>
int scoreBranchless(const std::uint8_t* p, const std::array<std::ptrdiff_t, N>& offsets) {
  constexpr int kArc = N / 2 + 1;
  const int v = p[0];
  std::int16_t d[N + kArc - 1];  // I(p) - x_i, circularly extended
  for (int i = 0; i < N; ++i)
    d[i] = static_cast<std::int16_t>(v - p[offsets[static_cast<std::size_t>(i)]]);
  for (int i = 0; i < kArc - 1; ++i) d[N + i] = d[i];
  std::int16_t lo[N], hi[N];  // min and max of d over the window starting at k
  for (int k = 0; k < N; ++k) lo[k] = hi[k] = d[k];
  for (int j = 1; j < kArc; ++j)
    for (int k = 0; k < N; ++k) {
      lo[k] = std::min(lo[k], d[k + j]);
      hi[k] = std::max(hi[k], d[k + j]);
    }
  // Darker arcs: min(p - x_i) = lo; brighter ones: min(x_i - p) = -hi.
  std::int16_t best = 1;
  for (int k = 0; k < N; ++k)
    best = std::max(best, std::max(lo[k], static_cast<std::int16_t>(-hi[k])));
  return std::min(best - 1, 254);
}

}  // namespace fast_detail

// Pointer offsets of a circle for a row stride (elements).
inline std::array<std::ptrdiff_t, 16> fastOffsets16(std::ptrdiff_t stride) {
  std::array<std::ptrdiff_t, 16> o{};
  for (std::size_t i = 0; i < 16; ++i) o[i] = kFastCircle16[i][0] + kFastCircle16[i][1] * stride;
  return o;
}
inline std::array<std::ptrdiff_t, 8> fastOffsets8(std::ptrdiff_t stride) {
  std::array<std::ptrdiff_t, 8> o{};
  for (std::size_t i = 0; i < 8; ++i) o[i] = kFastCircle8[i][0] + kFastCircle8[i][1] * stride;
  return o;
}

// FAST score of the pixel at p (see the header comment); precondition: its circle is inside
// the image.
inline int fastScore16(const std::uint8_t* p, const std::array<std::ptrdiff_t, 16>& offsets) {
  return fast_detail::scoreBranchless<16>(p, offsets);
}
inline int fastScore8(const std::uint8_t* p, const std::array<std::ptrdiff_t, 8>& offsets) {
  return fast_detail::scoreBranchless<8>(p, offsets);
}

// Score of (x, y) with either mask; 0 when the circle leaves the image.
inline int fastCornerScore(ImageView<const std::uint8_t> img, int x, int y, FastMask mask) {
  const int r = fastRadius(mask);
  if (x < r || y < r || x >= img.width - r || y >= img.height - r) return 0;
  const std::uint8_t* p = img.row(y) + x;
  return mask == FastMask::k9of16 ? fastScore16(p, fastOffsets16(img.stride))
                                  : fastScore8(p, fastOffsets8(img.stride));
}

// FAST 9-16 segment test at p for threshold t >= 1. Any run of 9 contiguous circle pixels holds
// one pixel of every opposite pair (i, i + 8), so the pairs reject most pixels before the full
// test: bit 0 = some darker, bit 1 = some brighter.
inline bool fastIsCorner16(const std::uint8_t* p, const std::array<std::ptrdiff_t, 16>& o, int t) {
  const int hi = p[0] + t, lo = p[0] - t;
  auto cls = [&](std::size_t i) {
    const int v = p[o[i]];
    return (v > hi ? 2 : 0) | (v < lo ? 1 : 0);
  };
  int d = cls(0) | cls(8);
  if (d == 0) return false;
  d &= cls(4) | cls(12);
  d &= cls(2) | cls(10);
  d &= cls(6) | cls(14);
  if (d == 0) return false;
  d &= cls(1) | cls(9);
  d &= cls(3) | cls(11);
  d &= cls(5) | cls(13);
  d &= cls(7) | cls(15);
  if (d == 0) return false;
  // Full test: bit masks of brighter / darker pixels, a circular run of 9 ones.
  std::uint32_t bright = 0, dark = 0;
  for (std::size_t i = 0; i < 16; ++i) {
    const int v = p[o[i]];
    bright |= static_cast<std::uint32_t>(v > hi) << i;
    dark |= static_cast<std::uint32_t>(v < lo) << i;
  }
  auto hasRun9 = [](std::uint32_t m) {
    m |= m << 16;                    // circular
    std::uint32_t r = m & (m >> 1);  // runs of 2 start here
    r &= r >> 2;                     // 4
    r &= r >> 4;                     // 8
    r &= m >> 8;                     // 9
    return (r & 0xFFFFu) != 0;
  };
  return hasRun9(bright) || hasRun9(dark);
}

// Calls onCorner(x, y, score) for every FAST 9-16 corner at threshold t (1..254) with
// border <= x < width - border and border <= y < height - border (border >= 3), in raster order.
template <class OnCorner>
void scanFast16(ImageView<const std::uint8_t> img, int t, int border, OnCorner&& onCorner) {
  border = std::max(border, 3);
  const auto o = fastOffsets16(img.stride);
  for (int y = border; y < img.height - border; ++y) {
    const std::uint8_t* row = img.row(y);
    for (int x = border; x < img.width - border; ++x)
      if (fastIsCorner16(row + x, o, t)) onCorner(x, y, fastScore16(row + x, o));
  }
}

struct FastCorner {
  int x = 0;      // column, px
  int y = 0;      // row, px
  int score = 0;  // FAST 9-16 score (see above), >= threshold
};

// Every FAST 9-16 corner at threshold t (1..254) without non-maximum suppression, raster order;
// pixels closer than 3 px to the border are never tested (the same set as
// cv::FAST(image, t, false, FastFeatureDetector::TYPE_9_16)).
inline void detectFastCorners(ImageView<const std::uint8_t> img, int t,
                              std::vector<FastCorner>& out) {
  out.clear();
  scanFast16(img, t, 3, [&](int x, int y, int s) { out.push_back({x, y, s}); });
}

}  // namespace svslam

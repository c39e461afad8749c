// AVX2 winner-take-all kernels of the stereo stage: the streaming left/right minimum over the
// aggregated cost planes and the cost look-ups at bidx -/+ 1. Bit-exact with
// stereo_kernels_scalar.cpp.
#include <immintrin.h>

#include <cstdlib>
#include <limits>

#include "simd/stereo_kernels.hpp"
#include "simd/stereo_kernels_avx2_detail.hpp"

namespace svslam::simd::avx2_detail {

namespace {

// The left state of 16 columns stays in registers across the planes; the branches of the
// reference become blends on unsigned minima (no bias needed):
//   bn = min(best, c); keep = (bn == best), i.e. not c < best
//   adj = (bidx == i - 1)                 (tested on the old bidx, as the reference does)
//   second = keep ? min(second, adj ? 0xFFFF : c) : pm2
//   bidx = keep ? bidx : i
// cm and cp are left to wtaNeighbours (fewer live registers: no spills in the plane loop).
// Left state of 16 columns at x; plane p is the row agg + p * stride (agg - stride: plane i0 - 1).
inline void wtaLeftBlock(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0,
                         std::uint16_t* best_p, std::int16_t* bidx_p, std::uint16_t* second_p,
                         std::uint16_t* pm1_p, std::uint16_t* pm2_p) {
  const __m256i one = _mm256_set1_epi16(1);
  __m256i best = loadu(best_p);
  __m256i second = loadu(second_p);
  __m256i pm1 = loadu(pm1_p);
  __m256i pm2 = loadu(pm2_p);
  // bidx1 = bidx + 1 and vi = i, so "i == bidx + 1" is one compare; i < 1024 (numDisp <= 1024)
  // fits int16 lanes.
  __m256i bidx1 = _mm256_add_epi16(loadu(bidx_p), one);
  __m256i vi = _mm256_set1_epi16(static_cast<short>(i0));
  // One plane: c is plane i, prev plane i - 1.
  const auto step = [&](__m256i c) {
    const __m256i vn = _mm256_add_epi16(vi, one);
    const __m256i bn = _mm256_min_epu16(best, c);
    const __m256i keep = _mm256_cmpeq_epi16(bn, best);
    const __m256i adj = _mm256_cmpeq_epi16(bidx1, vi);
    second = _mm256_blendv_epi8(pm2, _mm256_min_epu16(second, _mm256_or_si256(c, adj)), keep);
    bidx1 = _mm256_blendv_epi8(vn, bidx1, keep);
    best = bn;
    pm2 = pm1;
    pm1 = _mm256_min_epu16(pm1, c);
    vi = vn;
  };
  // Two planes per iteration, so the rotation pm2 <- pm1 needs no register copies.
  const std::uint16_t* a = agg;
  int p = 0;
  for (; p + 2 <= n_planes; p += 2, a += 2 * stride) {
    step(loadu(a));
    step(loadu(a + stride));
  }
  if (p < n_planes) step(loadu(a));
  const __m256i bidx = _mm256_sub_epi16(bidx1, one);
  storeu(best_p, best);
  storeu(second_p, second);
  storeu(pm1_p, pm1);
  storeu(pm2_p, pm2);
  storeu(bidx_p, bidx);
}

}  // namespace

// 8 pixels per step: rows bidx -/+ 1 clamped into [0, num_disp), gathered (32-bit, low half),
// 0xFFFF where the neighbour does not exist.
void wtaNeighbours(const std::uint16_t* agg, std::ptrdiff_t stride, int num_disp, int width,
                   const WtaRowState& s) {
  const __m256i zero = _mm256_setzero_si256();
  const __m256i one = _mm256_set1_epi32(1);
  const __m256i low = _mm256_set1_epi32(0xFFFF);
  const __m256i last = _mm256_set1_epi32(num_disp - 1);
  const __m256i vstride = _mm256_set1_epi32(static_cast<int>(stride));
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const int* base = reinterpret_cast<const int*>(agg);
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    const __m256i b =
        _mm256_cvtepi16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s.bidx + x)));
    const __m256i vx = _mm256_add_epi32(_mm256_set1_epi32(x), lanes);
    const __m256i rm = _mm256_max_epi32(_mm256_sub_epi32(b, one), zero);
    const __m256i rp = _mm256_min_epi32(_mm256_max_epi32(_mm256_add_epi32(b, one), zero), last);
    const __m256i gm = _mm256_and_si256(
        _mm256_i32gather_epi32(base, _mm256_add_epi32(_mm256_mullo_epi32(rm, vstride), vx), 2),
        low);
    const __m256i gp = _mm256_and_si256(
        _mm256_i32gather_epi32(base, _mm256_add_epi32(_mm256_mullo_epi32(rp, vstride), vx), 2),
        low);
    const __m256i has_m = _mm256_cmpgt_epi32(b, zero);  // b >= 1
    const __m256i has_p =
        _mm256_andnot_si256(_mm256_cmpgt_epi32(zero, b), _mm256_cmpgt_epi32(last, b));
    const __m256i cm = _mm256_blendv_epi8(low, gm, has_m);
    const __m256i cp = _mm256_blendv_epi8(low, gp, has_p);
    // packus: cm0-3 cp0-3 | cm4-7 cp4-7 (16-bit); 64-bit permute 0, 2, 1, 3 joins each half.
    const __m256i q = _mm256_permute4x64_epi64(_mm256_packus_epi32(cm, cp), 0xD8);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(s.cm + x), _mm256_castsi256_si128(q));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(s.cp + x), _mm256_extracti128_si256(q, 1));
  }
  if (x < width) wtaNeighboursRange(agg, stride, num_disp, x, width, s);
}

void wtaUpdateRows(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0, int width,
                   int d0, const WtaRowState& s) {
  int x = 0;
  if (n_planes > 0) {
    for (; x + 16 <= width; x += 16)
      wtaLeftBlock(agg + x, stride, n_planes, i0, s.best + x, s.bidx + x, s.second + x,
                   s.pm1 + x, s.pm2 + x);
  }
  if (x < width) wtaLeftTail(agg, stride, n_planes, i0, x, width, s);

  // Right image: plane i's candidate for right pixel xr is agg_i[xr + d0 + i]; it wins when
  // strictly below best_r, i.e. when min(best_r, c) differs from best_r. Right pixels that
  // every plane of the block reaches keep best_r / idx_r in registers across the planes; the
  // rest (near the right end, fewer planes) go plane by plane.
  if (n_planes <= 0) return;
  const int n_common = width - (d0 + i0 + n_planes - 1);  // right pixels all planes reach
  const __m256i one = _mm256_set1_epi16(1);
  int xr_common = 0;
  for (; xr_common + 16 <= n_common; xr_common += 16) {
    __m256i br = loadu(s.best_r + xr_common);
    __m256i ir = loadu(s.idx_r + xr_common);
    __m256i vi = _mm256_set1_epi16(static_cast<short>(i0));
    const std::uint16_t* a = agg + (d0 + i0) + xr_common;
    const auto step = [&](const std::uint16_t* q) {
      const __m256i nb = _mm256_min_epu16(br, loadu(q));
      ir = _mm256_blendv_epi8(vi, ir, _mm256_cmpeq_epi16(nb, br));
      br = nb;
      vi = _mm256_add_epi16(vi, one);
    };
    int p = 0;
    for (; p + 2 <= n_planes; p += 2, a += 2 * (stride + 1)) {  // two planes: no copies
      step(a);
      step(a + stride + 1);
    }
    if (p < n_planes) step(a);
    storeu(s.best_r + xr_common, br);
    storeu(s.idx_r + xr_common, ir);
  }
  for (int p = 0; p < n_planes; ++p) {
    const int i = i0 + p;
    const int n_right = width - (d0 + i);
    if (n_right <= xr_common) continue;
    const std::uint16_t* a = agg + p * stride + (d0 + i);
    const __m256i vi = _mm256_set1_epi16(static_cast<short>(i));
    int xr = xr_common;
    for (; xr + 16 <= n_right; xr += 16) {
      const __m256i br = loadu(s.best_r + xr);
      const __m256i nb = _mm256_min_epu16(br, loadu(a + xr));
      const __m256i keep = _mm256_cmpeq_epi16(nb, br);
      storeu(s.best_r + xr, nb);
      storeu(s.idx_r + xr, _mm256_blendv_epi8(vi, loadu(s.idx_r + xr), keep));
    }
    wtaRightTail(a, xr, n_right, i, s);
  }
}

}  // namespace svslam::simd::avx2_detail

namespace svslam::simd {

void wtaNeighboursAvx2(const std::uint16_t* agg, std::ptrdiff_t stride, int num_disp, int width,
                       const WtaRowState& s) {
  avx2_detail::wtaNeighbours(agg, stride, num_disp, width, s);
}

}  // namespace svslam::simd

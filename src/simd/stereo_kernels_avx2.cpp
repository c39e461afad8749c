// AVX2 backend of the stereo row kernels: 32 pixels per step for census and SAD, 16 uint16
// lanes per step elsewhere, scalar tails. Bit-exact with stereo_kernels_scalar.cpp.
#include <immintrin.h>

#include <array>
#include <cstdlib>
#include <limits>
#include <utility>

#include "simd/stereo_kernels.hpp"

namespace svslam::simd {

// 8 pixels per step in 32-bit lanes; every test of finalizeRange becomes a lane mask, the counts
// are per-lane accumulators (subtracting an all-ones mask adds 1), the look-ups are gathers.
void finalizeRowAvx2(const WtaRowState& s, const std::uint8_t* low_texture, int width,
                     const FinalizeParams& p, float* disp, float* sigma, float* curv,
                     FinalizeCounts& counts) {
  const __m256i zero = _mm256_setzero_si256();
  const __m256i ones = _mm256_set1_epi32(-1);
  const __m256i u16max = _mm256_set1_epi32(0xFFFF);
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i vd0 = _mm256_set1_epi32(p.d0);
  const __m256i last_idx = _mm256_set1_epi32(p.num_disp - 1);
  const __m256i wmax = _mm256_set1_epi32(width - 1);
  const __m256i lr_max = _mm256_set1_epi32(p.lr_max_diff);
  const __m256i max_denom = _mm256_set1_epi32(p.max_denom);
  const __m256i uniq_factor = _mm256_set1_epi32(100 + p.uniqueness_pct);
  const __m256i hundred = _mm256_set1_epi32(100);
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 inv_area = _mm256_set1_ps(p.inv_area);
  const __m256i use_uniq = p.uniqueness_pct > 0 ? ones : zero;
  const __m256i use_lr = p.lr_check ? ones : zero;
  const __m256i use_sub = p.subpixel ? ones : zero;
  __m256i n_nc = zero, n_lt = zero, n_nu = zero, n_lr = zero, n_ok = zero;
  const auto load8 = [](const void* q) {
    return _mm_loadu_si128(static_cast<const __m128i*>(q));
  };
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    const __m256i idx = _mm256_cvtepi16_epi32(load8(s.bidx + x));
    const __m256i best = _mm256_cvtepu16_epi32(load8(s.best + x));
    const __m256i second = _mm256_cvtepu16_epi32(load8(s.second + x));
    const __m256i cm = _mm256_cvtepu16_epi32(load8(s.cm + x));
    const __m256i cp = _mm256_cvtepu16_epi32(load8(s.cp + x));
    const __m256i no_cand = _mm256_cmpgt_epi32(zero, idx);
    __m256i low_tex = zero;
    if (low_texture != nullptr) {
      const __m256i t = _mm256_cvtepu8_epi32(_mm_loadl_epi64(
          reinterpret_cast<const __m128i*>(low_texture + x)));
      low_tex = _mm256_andnot_si256(_mm256_cmpeq_epi32(t, zero), ones);
    }
    // 100 second and (100 + u) best are below 2^31, so signed compares order them.
    const __m256i no_margin =
        _mm256_andnot_si256(_mm256_cmpgt_epi32(_mm256_mullo_epi32(second, hundred),
                                               _mm256_mullo_epi32(best, uniq_factor)),
                            ones);
    const __m256i not_unique =
        _mm256_and_si256(use_uniq, _mm256_or_si256(_mm256_cmpeq_epi32(second, u16max), no_margin));
    const __m256i vx = _mm256_add_epi32(_mm256_set1_epi32(x), lanes);
    const __m256i xr = _mm256_min_epi32(
        _mm256_max_epi32(_mm256_sub_epi32(vx, _mm256_add_epi32(vd0, idx)), zero), wmax);
    // 32-bit gather at idx_r + xr (2-byte scale): the low half is idx_r[xr].
    const __m256i g = _mm256_i32gather_epi32(reinterpret_cast<const int*>(s.idx_r), xr, 2);
    const __m256i idr = _mm256_srai_epi32(_mm256_slli_epi32(g, 16), 16);
    const __m256i lr_bad = _mm256_and_si256(
        use_lr, _mm256_or_si256(_mm256_cmpgt_epi32(zero, idr),
                                _mm256_cmpgt_epi32(_mm256_abs_epi32(_mm256_sub_epi32(idr, idx)),
                                                   lr_max)));
    // First failing test wins.
    const __m256i f1 = no_cand;
    const __m256i f2 = _mm256_andnot_si256(f1, low_tex);
    const __m256i any12 = _mm256_or_si256(f1, low_tex);
    const __m256i f3 = _mm256_andnot_si256(any12, not_unique);
    const __m256i any123 = _mm256_or_si256(any12, not_unique);
    const __m256i f4 = _mm256_andnot_si256(any123, lr_bad);
    const __m256i invalid = _mm256_or_si256(any123, lr_bad);
    n_nc = _mm256_sub_epi32(n_nc, f1);
    n_lt = _mm256_sub_epi32(n_lt, f2);
    n_nu = _mm256_sub_epi32(n_nu, f3);
    n_lr = _mm256_sub_epi32(n_lr, f4);
    n_ok = _mm256_sub_epi32(n_ok, _mm256_xor_si256(invalid, ones));

    const __m256i denom = _mm256_sub_epi32(_mm256_add_epi32(cm, cp), _mm256_add_epi32(best, best));
    const __m256i parabola = _mm256_and_si256(
        _mm256_and_si256(_mm256_cmpgt_epi32(idx, zero), _mm256_cmpgt_epi32(last_idx, idx)),
        _mm256_andnot_si256(_mm256_cmpeq_epi32(cp, u16max), _mm256_cmpgt_epi32(denom, zero)));
    const __m256i safe_denom = _mm256_blendv_epi8(_mm256_set1_epi32(1), denom, parabola);
    const __m256 q = _mm256_div_ps(_mm256_cvtepi32_ps(_mm256_sub_epi32(cm, cp)),
                                   _mm256_cvtepi32_ps(_mm256_add_epi32(safe_denom, safe_denom)));
    const __m256 delta =
        _mm256_and_ps(q, _mm256_castsi256_ps(_mm256_and_si256(parabola, use_sub)));
    const __m256 d = _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(vd0, idx)), delta);
    const __m256i tab_i = _mm256_and_si256(_mm256_min_epi32(denom, max_denom), parabola);
    const __m256 sg = _mm256_i32gather_ps(p.sigma_by_denom, tab_i, 4);
    const __m256 cv = _mm256_and_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(denom), inv_area),
                                    _mm256_castsi256_ps(parabola));
    const __m256 inval = _mm256_castsi256_ps(invalid);
    _mm256_storeu_ps(disp + x, _mm256_blendv_ps(d, inf, inval));
    _mm256_storeu_ps(sigma + x, _mm256_blendv_ps(sg, inf, inval));
    _mm256_storeu_ps(curv + x, _mm256_blendv_ps(cv, inf, inval));
  }
  const auto sum8 = [](__m256i v) {
    alignas(32) int t[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(t), v);
    return t[0] + t[1] + t[2] + t[3] + t[4] + t[5] + t[6] + t[7];
  };
  counts.no_candidate += sum8(n_nc);
  counts.low_texture += sum8(n_lt);
  counts.not_unique += sum8(n_nu);
  counts.lr_inconsistent += sum8(n_lr);
  counts.valid += sum8(n_ok);
  if (x < width) finalizeRange(s, low_texture, x, width, p, disp, sigma, curv, counts);
}

namespace {

inline __m256i loadu(const void* p) { return _mm256_loadu_si256(static_cast<const __m256i*>(p)); }
inline void storeu(void* p, __m256i v) { _mm256_storeu_si256(static_cast<__m256i*>(p), v); }

// Byte plane j holds census offsets 8j..8j+7 of 32 pixels, MSB first; it is byte 7 - j of each
// pixel's word. Transposes the planes into 32 words: unpack 8 -> 16 -> 32 bits within lanes
// (pixels p and p + 16 share a lane position), then join the lanes.
inline void transposeStore(const __m256i* pl, std::uint64_t* out) {
  const __m256i a = _mm256_unpacklo_epi8(pl[7], pl[6]);  // pixels 0-7 | 16-23
  const __m256i b = _mm256_unpackhi_epi8(pl[7], pl[6]);  // pixels 8-15 | 24-31
  const __m256i c = _mm256_unpacklo_epi8(pl[5], pl[4]);
  const __m256i d = _mm256_unpackhi_epi8(pl[5], pl[4]);
  const __m256i e = _mm256_unpacklo_epi8(pl[3], pl[2]);
  const __m256i f = _mm256_unpackhi_epi8(pl[3], pl[2]);
  const __m256i g = _mm256_unpacklo_epi8(pl[1], pl[0]);
  const __m256i h = _mm256_unpackhi_epi8(pl[1], pl[0]);
  const __m256i ac_lo = _mm256_unpacklo_epi16(a, c);  // pixels 0-3 | 16-19, bytes 0-3 of words
  const __m256i ac_hi = _mm256_unpackhi_epi16(a, c);  // 4-7 | 20-23
  const __m256i eg_lo = _mm256_unpacklo_epi16(e, g);  // bytes 4-7 of words
  const __m256i eg_hi = _mm256_unpackhi_epi16(e, g);
  const __m256i bd_lo = _mm256_unpacklo_epi16(b, d);  // 8-11 | 24-27
  const __m256i bd_hi = _mm256_unpackhi_epi16(b, d);  // 12-15 | 28-31
  const __m256i fh_lo = _mm256_unpacklo_epi16(f, h);
  const __m256i fh_hi = _mm256_unpackhi_epi16(f, h);
  const __m256i w0 = _mm256_unpacklo_epi32(ac_lo, eg_lo);  // 0,1 | 16,17
  const __m256i w1 = _mm256_unpackhi_epi32(ac_lo, eg_lo);  // 2,3 | 18,19
  const __m256i w2 = _mm256_unpacklo_epi32(ac_hi, eg_hi);  // 4,5 | 20,21
  const __m256i w3 = _mm256_unpackhi_epi32(ac_hi, eg_hi);  // 6,7 | 22,23
  const __m256i w4 = _mm256_unpacklo_epi32(bd_lo, fh_lo);  // 8,9 | 24,25
  const __m256i w5 = _mm256_unpackhi_epi32(bd_lo, fh_lo);  // 10,11 | 26,27
  const __m256i w6 = _mm256_unpacklo_epi32(bd_hi, fh_hi);  // 12,13 | 28,29
  const __m256i w7 = _mm256_unpackhi_epi32(bd_hi, fh_hi);  // 14,15 | 30,31
  storeu(out + 0, _mm256_permute2x128_si256(w0, w1, 0x20));
  storeu(out + 4, _mm256_permute2x128_si256(w2, w3, 0x20));
  storeu(out + 8, _mm256_permute2x128_si256(w4, w5, 0x20));
  storeu(out + 12, _mm256_permute2x128_si256(w6, w7, 0x20));
  storeu(out + 16, _mm256_permute2x128_si256(w0, w1, 0x31));
  storeu(out + 20, _mm256_permute2x128_si256(w2, w3, 0x31));
  storeu(out + 24, _mm256_permute2x128_si256(w4, w5, 0x31));
  storeu(out + 28, _mm256_permute2x128_si256(w6, w7, 0x31));
}

// 32 pixels of a census row; W, H are compile-time window sides in the unrolled instances and
// 0 in the generic one (then win_w, win_h are used). Bit "neighbour < centre" enters the low end
// of a byte accumulator as acc = 2 acc + 1 + m with m = -1 when max(nb, c) == nb (nb >= c);
// the 1s of 8 steps sum to 255, so acc is kept without them and 255 is added per full byte.
template <int W, int H>
inline void census32Planes(const std::uint8_t* win, std::ptrdiff_t stride, int win_w, int win_h,
                           __m256i* planes) {
  const int ww = W > 0 ? W : win_w;
  const int wh = H > 0 ? H : win_h;
  const int cx = ww / 2;
  const int cy = wh / 2;
  const __m256i c = loadu(win + cy * stride + cx);
  const __m256i ff = _mm256_set1_epi8(-1);
  for (int j = 0; j < 8; ++j) planes[j] = _mm256_setzero_si256();
  __m256i acc = _mm256_setzero_si256();
  int k = 0;
#pragma GCC unroll 16
  for (int dy = 0; dy < wh; ++dy) {
    const std::uint8_t* r = win + dy * stride;
#pragma GCC unroll 16
    for (int dx = 0; dx < ww; ++dx) {
      if (dy == cy && dx == cx) continue;
      const __m256i nb = loadu(r + dx);
      const __m256i ge = _mm256_cmpeq_epi8(_mm256_max_epu8(nb, c), nb);
      acc = _mm256_add_epi8(_mm256_add_epi8(acc, acc), ge);
      if ((++k & 7) == 0) {
        planes[(k >> 3) - 1] = _mm256_add_epi8(acc, ff);  // + 255 (mod 256)
        acc = _mm256_setzero_si256();
      }
    }
  }
  if ((k & 7) != 0) {  // partial last plane: its ones sum to 2^n - 1; then shift up to bit 7
    acc = _mm256_add_epi8(acc, _mm256_set1_epi8(static_cast<char>((1 << (k & 7)) - 1)));
    for (int s = k & 7; s < 8; ++s) acc = _mm256_add_epi8(acc, acc);
    planes[k >> 3] = acc;
  }
}

template <int W, int H>
inline void census32(const std::uint8_t* win, std::ptrdiff_t stride, int win_w, int win_h,
                     std::uint64_t* out) {
  __m256i planes[8];
  census32Planes<W, H>(win, stride, win_w, win_h, planes);
  transposeStore(planes, out);
}

template <int W, int H>
void censusRowT(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w, int win_h,
                std::uint64_t* out) {
  int x = 0;
  for (; x + 32 <= width; x += 32) census32<W, H>(win + x, stride, win_w, win_h, out + x);
  if (x < width) scalarKernels().censusRow(win + x, stride, width - x, win_w, win_h, out + x);
}

void censusRow(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w, int win_h,
               std::uint64_t* out) {
  // Fully unrolled for the windows the stage is used with; any other size takes the loop.
  if (win_w == 9 && win_h == 7) return censusRowT<9, 7>(win, stride, width, win_w, win_h, out);
  if (win_w == 7 && win_h == 9) return censusRowT<7, 9>(win, stride, width, win_w, win_h, out);
  if (win_w == 7 && win_h == 7) return censusRowT<7, 7>(win, stride, width, win_w, win_h, out);
  if (win_w == 5 && win_h == 5) return censusRowT<5, 5>(win, stride, width, win_w, win_h, out);
  censusRowT<0, 0>(win, stride, width, win_w, win_h, out);
}

template <int W, int H>
void censusPlanesRowT(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w,
                      int win_h, std::uint8_t* out, std::ptrdiff_t plane_stride) {
  int x = 0;
  for (; x + 32 <= width; x += 32) {
    __m256i planes[8];
    census32Planes<W, H>(win + x, stride, win_w, win_h, planes);
    for (int j = 0; j < 8; ++j) storeu(out + j * plane_stride + x, planes[j]);
  }
  if (x < width)
    scalarKernels().censusPlanesRow(win + x, stride, width - x, win_w, win_h, out + x,
                                    plane_stride);
}

void censusPlanesRow(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w,
                     int win_h, std::uint8_t* out, std::ptrdiff_t plane_stride) {
  if (win_w == 9 && win_h == 7)
    return censusPlanesRowT<9, 7>(win, stride, width, win_w, win_h, out, plane_stride);
  if (win_w == 7 && win_h == 9)
    return censusPlanesRowT<7, 9>(win, stride, width, win_w, win_h, out, plane_stride);
  if (win_w == 7 && win_h == 7)
    return censusPlanesRowT<7, 7>(win, stride, width, win_w, win_h, out, plane_stride);
  if (win_w == 5 && win_h == 5)
    return censusPlanesRowT<5, 5>(win, stride, width, win_w, win_h, out, plane_stride);
  censusPlanesRowT<0, 0>(win, stride, width, win_w, win_h, out, plane_stride);
}

// Byte-plane Hamming costs of 32 pixels per step: the left planes stay in registers across the
// disparities; per plane one xor and a nibble look-up (vpshufb) per half byte, summed in bytes
// (at most 64, no overflow), no horizontal reduction.
template <int NP>
void censusPlanesCostT(const std::uint8_t* left, const std::uint8_t* right,
                       std::ptrdiff_t plane_stride, int width, int d_first, int n_d,
                       std::uint8_t* cost, std::ptrdiff_t cost_stride) {
  const __m256i lut = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4,  //
                                       0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i nibble = _mm256_set1_epi8(0x0F);
  int x = 0;
  for (; x + 32 <= width; x += 32) {
    __m256i l[NP];
    for (int j = 0; j < NP; ++j) l[j] = loadu(left + j * plane_stride + x);
    const std::uint8_t* r = right + x - d_first;
    std::uint8_t* out = cost + x;
    if constexpr (NP == 8) {
      // Eight planes through a carry-save adder tree first (full adder: s = a ^ b ^ c,
      // carry = ab | (a ^ b) c, so a + b + c = s + 2 carry bitwise): popcount =
      // pop(s3) + pop(x7) + 2 (pop(t) + 2 pop(f)), four look-up pairs instead of eight.
      const auto pop = [&](__m256i v) {
        return _mm256_add_epi8(_mm256_shuffle_epi8(lut, _mm256_and_si256(v, nibble)),
                               _mm256_shuffle_epi8(
                                   lut, _mm256_and_si256(_mm256_srli_epi16(v, 4), nibble)));
      };
      const auto fa = [](__m256i a, __m256i b, __m256i c, __m256i& sum, __m256i& carry) {
        const __m256i u = _mm256_xor_si256(a, b);
        sum = _mm256_xor_si256(u, c);
        carry = _mm256_or_si256(_mm256_and_si256(a, b), _mm256_and_si256(u, c));
      };
      for (int k = 0; k < n_d; ++k, --r, out += cost_stride) {
        const auto xj = [&](int j) { return _mm256_xor_si256(l[j], loadu(r + j * plane_stride)); };
        __m256i s1, c1, s2, c2, s3, c3, t, f;
        fa(xj(0), xj(1), xj(2), s1, c1);
        fa(xj(3), xj(4), xj(5), s2, c2);
        fa(s1, s2, xj(6), s3, c3);
        fa(c1, c2, c3, t, f);
        const __m256i pf = pop(f);
        const __m256i w2 = _mm256_add_epi8(pop(t), _mm256_add_epi8(pf, pf));
        storeu(out, _mm256_add_epi8(_mm256_add_epi8(pop(s3), pop(xj(7))),
                                    _mm256_add_epi8(w2, w2)));
      }
      continue;
    }
    for (int k = 0; k < n_d; ++k, --r, out += cost_stride) {
      __m256i acc0 = _mm256_setzero_si256();
      __m256i acc1 = _mm256_setzero_si256();
      for (int j = 0; j < NP; ++j) {
        const __m256i v = _mm256_xor_si256(l[j], loadu(r + j * plane_stride));
        acc0 = _mm256_add_epi8(acc0, _mm256_shuffle_epi8(lut, _mm256_and_si256(v, nibble)));
        acc1 = _mm256_add_epi8(
            acc1, _mm256_shuffle_epi8(lut, _mm256_and_si256(_mm256_srli_epi16(v, 4), nibble)));
      }
      storeu(out, _mm256_add_epi8(acc0, acc1));
    }
  }
  if (x < width)
    scalarKernels().censusPlanesCostRows(left + x, right + x, plane_stride, NP, width - x,
                                         d_first, n_d, cost + x, cost_stride);
}

using PlanesCostFn = void (*)(const std::uint8_t*, const std::uint8_t*, std::ptrdiff_t, int, int,
                              int, std::uint8_t*, std::ptrdiff_t);
constexpr PlanesCostFn kPlanesCostFns[8] = {
    &censusPlanesCostT<1>, &censusPlanesCostT<2>, &censusPlanesCostT<3>, &censusPlanesCostT<4>,
    &censusPlanesCostT<5>, &censusPlanesCostT<6>, &censusPlanesCostT<7>, &censusPlanesCostT<8>};

void censusPlanesCostRows(const std::uint8_t* left, const std::uint8_t* right,
                          std::ptrdiff_t plane_stride, int n_planes, int width, int d_first,
                          int n_d, std::uint8_t* cost, std::ptrdiff_t cost_stride) {
  kPlanesCostFns[n_planes - 1](left, right, plane_stride, width, d_first, n_d, cost,
                               cost_stride);
}

// Population count of each 64-bit element (in its low 16 bits, the rest zero).
inline __m256i popcount64(__m256i v) {
  const __m256i lut = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4,  //
                                       0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i nibble = _mm256_set1_epi8(0x0F);
  const __m256i lo = _mm256_and_si256(v, nibble);
  const __m256i hi = _mm256_and_si256(_mm256_srli_epi16(v, 4), nibble);
  const __m256i bytes = _mm256_add_epi8(_mm256_shuffle_epi8(lut, lo), _mm256_shuffle_epi8(lut, hi));
  return _mm256_sad_epu8(bytes, _mm256_setzero_si256());
}

void censusCostRow(const std::uint64_t* left, const std::uint64_t* right, int width, int d,
                   std::uint8_t* cost) {
  const std::uint64_t* r = right - d;
  const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
  int x = 0;
  for (; x + 16 <= width; x += 16) {
    const __m256i p0 = popcount64(_mm256_xor_si256(loadu(left + x), loadu(r + x)));
    const __m256i p1 = popcount64(_mm256_xor_si256(loadu(left + x + 4), loadu(r + x + 4)));
    const __m256i p2 = popcount64(_mm256_xor_si256(loadu(left + x + 8), loadu(r + x + 8)));
    const __m256i p3 = popcount64(_mm256_xor_si256(loadu(left + x + 12), loadu(r + x + 12)));
    // 16-bit lanes after two packs: 0,1,4,5,8,9,12,13 | 2,3,6,7,10,11,14,15; the permute puts
    // them in pixel order, the last pack narrows them to bytes.
    const __m256i q = _mm256_permutevar8x32_epi32(
        _mm256_packus_epi32(_mm256_packus_epi32(p0, p1), _mm256_packus_epi32(p2, p3)), order);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(cost + x),
                     _mm_packus_epi16(_mm256_castsi256_si128(q), _mm256_extracti128_si256(q, 1)));
  }
  for (; x < width; ++x) cost[x] = static_cast<std::uint8_t>(_mm_popcnt_u64(left[x] ^ r[x]));
}

void sadCostRow(const std::uint8_t* left, const std::uint8_t* right, int width, int d,
                std::uint8_t* cost) {
  const std::uint8_t* r = right - d;
  int x = 0;
  for (; x + 32 <= width; x += 32) {
    const __m256i a = loadu(left + x);
    const __m256i b = loadu(r + x);
    storeu(cost + x, _mm256_or_si256(_mm256_subs_epu8(a, b), _mm256_subs_epu8(b, a)));
  }
  if (x + 16 <= width) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(left + x));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(r + x));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(cost + x),
                     _mm_or_si128(_mm_subs_epu8(a, b), _mm_subs_epu8(b, a)));
    x += 16;
  }
  for (; x < width; ++x) cost[x] = static_cast<std::uint8_t>(std::abs(left[x] - r[x]));
}

inline __m256i loadU8AsU16(const std::uint8_t* p) {
  return _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
}

void addSubRow(std::uint16_t* acc, const std::uint8_t* add, const std::uint8_t* sub,
               std::size_t n) {
  std::size_t j = 0;
  if (sub == nullptr) {
    for (; j + 16 <= n; j += 16)
      storeu(acc + j, _mm256_add_epi16(loadu(acc + j), loadU8AsU16(add + j)));
    for (; j < n; ++j) acc[j] = static_cast<std::uint16_t>(acc[j] + add[j]);
  } else {
    for (; j + 16 <= n; j += 16) {
      const __m256i s = _mm256_add_epi16(loadu(acc + j), loadU8AsU16(add + j));
      storeu(acc + j, _mm256_sub_epi16(s, loadU8AsU16(sub + j)));
    }
    for (; j < n; ++j) acc[j] = static_cast<std::uint16_t>(acc[j] + add[j] - sub[j]);
  }
}

// Box of a fixed odd width K: one load plus K - 1 adds with memory operands per 16 outputs.
template <int K>
void boxFixed(const std::uint16_t* in, int width, std::uint16_t* out) {
  int x = 0;
  for (; x + 16 <= width; x += 16) {
    __m256i s0 = loadu(in + x);
    __m256i s1 = _mm256_setzero_si256();
    for (int k = 1; k + 1 < K; k += 2) {  // two independent chains
      s0 = _mm256_add_epi16(s0, loadu(in + x + k));
      s1 = _mm256_add_epi16(s1, loadu(in + x + k + 1));
    }
    storeu(out + x, _mm256_add_epi16(s0, s1));
  }
  for (; x < width; ++x) {
    std::uint16_t s = 0;
    for (int k = 0; k < K; ++k) s = static_cast<std::uint16_t>(s + in[x + k]);
    out[x] = s;
  }
}

using BoxFn = void (*)(const std::uint16_t*, int, std::uint16_t*);
template <int... K>
constexpr auto boxTable(std::integer_sequence<int, K...>) {
  return std::array<BoxFn, sizeof...(K)>{&boxFixed<2 * K + 1>...};
}
// boxFixed<2j + 1> for j = 0 .. 15, i.e. every odd width 1..31 the stage accepts.
constexpr auto kBoxFns = boxTable(std::make_integer_sequence<int, 16>{});

void boxRow(const std::uint16_t* in, int width, int win_w, std::uint16_t* out) {
  if (win_w % 2 == 1 && win_w <= 31) {
    kBoxFns[static_cast<std::size_t>(win_w / 2)](in, width, out);
    return;
  }
  int x = 0;
  for (; x + 16 <= width; x += 16) {
    __m256i s0 = _mm256_setzero_si256();
    __m256i s1 = _mm256_setzero_si256();
    int k = 0;
    for (; k + 2 <= win_w; k += 2) {
      s0 = _mm256_add_epi16(s0, loadu(in + x + k));
      s1 = _mm256_add_epi16(s1, loadu(in + x + k + 1));
    }
    if (k < win_w) s0 = _mm256_add_epi16(s0, loadu(in + x + k));
    storeu(out + x, _mm256_add_epi16(s0, s1));
  }
  for (; x < width; ++x) {
    std::uint16_t s = 0;
    for (int k = 0; k < win_w; ++k) s = static_cast<std::uint16_t>(s + in[x + k]);
    out[x] = s;
  }
}

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

}  // namespace

const StereoKernels& avx2Kernels() {
  static const StereoKernels k{Backend::kAvx2, "avx2",    censusRow, censusCostRow,
                               sadCostRow,     addSubRow, boxRow,    wtaUpdateRows,
                               wtaNeighbours,  finalizeRowAvx2, censusPlanesRow,
                               censusPlanesCostRows};
  return k;
}

}  // namespace svslam::simd

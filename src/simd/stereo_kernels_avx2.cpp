// AVX2 backend of the stereo row kernels: 32 pixels per step for census and SAD, 16 uint16
// lanes per step elsewhere, scalar tails. Bit-exact with stereo_kernels_scalar.cpp. The
// winner-take-all kernels are in stereo_kernels_avx2_wta.cpp, finalizeRow in
// stereo_kernels_avx2_finalize.cpp.
#include <immintrin.h>

#include <array>
#include <cstdlib>
#include <limits>
#include <utility>

#include "simd/stereo_kernels.hpp"
#include "simd/stereo_kernels_avx2_detail.hpp"

namespace svslam::simd {

namespace {

using avx2_detail::loadu;
using avx2_detail::storeu;

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

}  // namespace

const StereoKernels& avx2Kernels() {
  static const StereoKernels k{Backend::kAvx2, "avx2",    censusRow, censusCostRow,
                               sadCostRow,     addSubRow, boxRow,    avx2_detail::wtaUpdateRows,
                               avx2_detail::wtaNeighbours,  finalizeRowAvx2, censusPlanesRow,
                               censusPlanesCostRows};
  return k;
}

}  // namespace svslam::simd

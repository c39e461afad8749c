// AVX-512 (F, BW, VL, VPOPCNTDQ, BITALG) backend of the stereo row kernels. Compiled with its
// own instruction-set flags and selected at run time; bit-exact with stereo_kernels_scalar.cpp.
// Vector bodies work on 32 x uint16 or 64 x uint8 columns; tails use masked loads and stores, or
// (for the per-column kernels) the scalar reference at an offset. The neighbour look-up
// (gathers) is the AVX2 kernel, shared rather than rewritten; finalizeRow is in
// stereo_kernels_avx512_finalize.cpp.
#include <immintrin.h>

#include <algorithm>
#include <array>

#include "simd/stereo_kernels.hpp"

namespace svslam::simd {
namespace {

// Census words from 8 byte planes: plane j holds census bits 8j..8j+7 (MSB first) of each pixel
// and becomes byte 7 - j (little endian) of the pixel's word.
// 8 byte planes of 32 pixels (256-bit) -> 32 census words at out[0..32).
inline void transposeStore256(const __m256i p[8], std::uint64_t* out) {
  const __m256i t0 = _mm256_unpacklo_epi8(p[7], p[6]), t1 = _mm256_unpackhi_epi8(p[7], p[6]);
  const __m256i t2 = _mm256_unpacklo_epi8(p[5], p[4]), t3 = _mm256_unpackhi_epi8(p[5], p[4]);
  const __m256i t4 = _mm256_unpacklo_epi8(p[3], p[2]), t5 = _mm256_unpackhi_epi8(p[3], p[2]);
  const __m256i t6 = _mm256_unpacklo_epi8(p[1], p[0]), t7 = _mm256_unpackhi_epi8(p[1], p[0]);
  const __m256i u0 = _mm256_unpacklo_epi16(t0, t2), u1 = _mm256_unpackhi_epi16(t0, t2);
  const __m256i u2 = _mm256_unpacklo_epi16(t1, t3), u3 = _mm256_unpackhi_epi16(t1, t3);
  const __m256i u4 = _mm256_unpacklo_epi16(t4, t6), u5 = _mm256_unpackhi_epi16(t4, t6);
  const __m256i u6 = _mm256_unpacklo_epi16(t5, t7), u7 = _mm256_unpackhi_epi16(t5, t7);
  __m256i w[8];
  w[0] = _mm256_unpacklo_epi32(u0, u4);  // pixels 0,1 | 16,17
  w[1] = _mm256_unpackhi_epi32(u0, u4);  // 2,3 | 18,19
  w[2] = _mm256_unpacklo_epi32(u1, u5);
  w[3] = _mm256_unpackhi_epi32(u1, u5);
  w[4] = _mm256_unpacklo_epi32(u2, u6);
  w[5] = _mm256_unpackhi_epi32(u2, u6);
  w[6] = _mm256_unpacklo_epi32(u3, u7);
  w[7] = _mm256_unpackhi_epi32(u3, u7);
  for (int m = 0; m < 8; m += 2) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + 2 * m),
                        _mm256_permute2x128_si256(w[m], w[m + 1], 0x20));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + 16 + 2 * m),
                        _mm256_permute2x128_si256(w[m], w[m + 1], 0x31));
  }
}

// 256-bit steps: the 62 window loads are misaligned, and a misaligned 512-bit load always
// splits across cache lines.
void censusRow(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w, int win_h,
               std::uint64_t* out) {
  const int cx = win_w / 2;
  const int cy = win_h / 2;
  const int n_off = win_w * win_h - 1;
  std::ptrdiff_t off[64];  // offset k -> position in the window, row-major, centre skipped
  for (int dy = 0, k = 0; dy < win_h; ++dy)
    for (int dx = 0; dx < win_w; ++dx)
      if (dy != cy || dx != cx) off[k++] = dy * stride + dx;
  // Unsigned p < c as a signed compare of p ^ 0x80 and c ^ 0x80: t = -1 where p < c, and
  // acc = 2 acc - t appends the bit. Plain vector ops, no mask registers.
  const __m256i flip = _mm256_set1_epi8(static_cast<char>(0x80));
  int x = 0;
  for (; x + 32 <= width; x += 32) {
    const __m256i c = _mm256_xor_si256(
        _mm256_loadu_si256(reinterpret_cast<const __m256i*>(win + cy * stride + cx + x)), flip);
    __m256i planes[8];
    for (int j = 0; j < 8; ++j) {
      // Plane j accumulates offsets 8j .. 8j+7 in a register, MSB first.
      __m256i acc = _mm256_setzero_si256();
      const int k_end = std::min(n_off, 8 * j + 8);
      for (int k = 8 * j; k < k_end; ++k) {
        const __m256i p = _mm256_xor_si256(
            _mm256_loadu_si256(reinterpret_cast<const __m256i*>(win + off[k] + x)), flip);
        acc = _mm256_sub_epi8(_mm256_add_epi8(acc, acc), _mm256_cmpgt_epi8(c, p));
      }
      // A partial plane still puts offset k at bit 63 - k: shift it up to the MSB.
      for (int k = std::max(k_end, 8 * j); k < 8 * j + 8 && k_end > 8 * j; ++k)
        acc = _mm256_add_epi8(acc, acc);
      planes[j] = acc;
    }
    transposeStore256(planes, out + x);
  }
  if (x < width) scalarKernels().censusRow(win + x, stride, width - x, win_w, win_h, out + x);
}

inline __mmask32 tailMask32(int n) {
  return n >= 32 ? 0xFFFFFFFFu : (n <= 0 ? 0u : ((1u << n) - 1u));
}
inline __mmask64 tailMask64(int n) {
  return n >= 64 ? ~__mmask64{0} : (n <= 0 ? __mmask64{0} : ((__mmask64{1} << n) - 1u));
}

// Byte-plane census of 64 pixels per step (StereoKernels::censusPlanesRow). W, H are the window
// sides in the unrolled instances and 0 in the generic one. Per neighbour one compare into a
// mask and one masked add of its bit: offset 8j + b sets bit 7 - b of plane j where
// neighbour < centre. Ragged end: masked loads and stores (masked-out lanes are never read).
template <int W, int H>
void censusPlanesRowT(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w,
                      int win_h, std::uint8_t* out, std::ptrdiff_t plane_stride) {
  const int ww = W > 0 ? W : win_w;
  const int wh = H > 0 ? H : win_h;
  const int cx = ww / 2;
  const int cy = wh / 2;
  __m512i bit[8];  // the b-th neighbour of a plane sets bit 7 - b
  for (int b = 0; b < 8; ++b) bit[b] = _mm512_set1_epi8(static_cast<char>(0x80 >> b));
  for (int x = 0; x < width; x += 64) {
    const __mmask64 m = tailMask64(width - x);
    const std::uint8_t* w = win + x;
    const __m512i c = _mm512_maskz_loadu_epi8(m, w + cy * stride + cx);
    __m512i acc = _mm512_setzero_si512();
    int k = 0;
#pragma GCC unroll 16
    for (int dy = 0; dy < wh; ++dy) {
#pragma GCC unroll 16
      for (int dx = 0; dx < ww; ++dx) {
        if (dy == cy && dx == cx) continue;
        const __mmask64 lt =
            _mm512_cmplt_epu8_mask(_mm512_maskz_loadu_epi8(m, w + dy * stride + dx), c);
        acc = _mm512_mask_add_epi8(acc, lt, acc, bit[k & 7]);  // disjoint bits: add = or
        if ((++k & 7) == 0) {
          _mm512_mask_storeu_epi8(out + ((k >> 3) - 1) * plane_stride + x, m, acc);
          acc = _mm512_setzero_si512();
        }
      }
    }
    if ((k & 7) != 0) _mm512_mask_storeu_epi8(out + (k >> 3) * plane_stride + x, m, acc);
    for (int j = (k + 7) >> 3; j < 8; ++j)  // planes past the window's bits are zero
      _mm512_mask_storeu_epi8(out + j * plane_stride + x, m, _mm512_setzero_si512());
  }
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

// Byte-plane Hamming costs of 64 pixels per step (StereoKernels::censusPlanesCostRows): the
// left planes stay in registers across the disparities; per plane one xor and one byte
// population count (VPOPCNTB), summed in bytes (at most 64, no overflow). The ragged end uses
// masked loads and stores (masked-out lanes are never read).
template <int NP>
void censusPlanesCostT(const std::uint8_t* left, const std::uint8_t* right,
                       std::ptrdiff_t plane_stride, int width, int d_first, int n_d,
                       std::uint8_t* cost, std::ptrdiff_t cost_stride) {
  for (int x = 0; x < width; x += 64) {
    const __mmask64 m = tailMask64(width - x);
    __m512i l[NP];
    for (int j = 0; j < NP; ++j) l[j] = _mm512_maskz_loadu_epi8(m, left + j * plane_stride + x);
    const std::uint8_t* r = right + x - d_first;
    std::uint8_t* out = cost + x;
    for (int k = 0; k < n_d; ++k, --r, out += cost_stride) {
      __m512i acc = _mm512_popcnt_epi8(_mm512_xor_si512(l[0], _mm512_maskz_loadu_epi8(m, r)));
      for (int j = 1; j < NP; ++j)
        acc = _mm512_add_epi8(acc, _mm512_popcnt_epi8(_mm512_xor_si512(
                                       l[j], _mm512_maskz_loadu_epi8(m, r + j * plane_stride))));
      _mm512_mask_storeu_epi8(out, m, acc);
    }
  }
}

using PlanesCostFn = void (*)(const std::uint8_t*, const std::uint8_t*, std::ptrdiff_t, int, int,
                              int, std::uint8_t*, std::ptrdiff_t);
constexpr PlanesCostFn kPlanesCostFns[8] = {
    &censusPlanesCostT<1>, &censusPlanesCostT<2>, &censusPlanesCostT<3>, &censusPlanesCostT<4>,
    &censusPlanesCostT<5>, &censusPlanesCostT<6>, &censusPlanesCostT<7>, &censusPlanesCostT<8>};

void censusPlanesCostRows(const std::uint8_t* left, const std::uint8_t* right,
                          std::ptrdiff_t plane_stride, int n_planes, int width, int d_first,
                          int n_d, std::uint8_t* cost, std::ptrdiff_t cost_stride) {
  kPlanesCostFns[n_planes - 1](left, right, plane_stride, width, d_first, n_d, cost, cost_stride);
}

void censusCostRow(const std::uint64_t* left, const std::uint64_t* right, int width, int d,
                   std::uint8_t* cost) {
  const std::uint64_t* r = right - d;
  int x = 0;
  // 256-bit right loads (see boxRow); four popcount vectors packed to 16 bytes.
  for (; x + 16 <= width; x += 16) {
    __m256i pc[4];
    for (int q = 0; q < 4; ++q)
      pc[q] = _mm256_popcnt_epi64(
          _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(left + x + 4 * q)),
                           _mm256_loadu_si256(reinterpret_cast<const __m256i*>(r + x + 4 * q))));
    // Each 64-bit lane holds a count <= 64: pack 64 -> 32 -> 16 -> 8 bits keeping pixel order.
    const __m512i all = _mm512_inserti64x4(
        _mm512_castsi256_si512(_mm256_or_si256(pc[0], _mm256_slli_epi64(pc[1], 32))),
        _mm256_or_si256(pc[2], _mm256_slli_epi64(pc[3], 32)), 1);
    // all (32-bit lanes): p0 p4 p1 p5 p2 p6 p3 p7 | p8 p12 p9 p13 p10 p14 p11 p15
    const __m512i order = _mm512_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7, 8, 10, 12, 14, 9, 11, 13, 15);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(cost + x),
                     _mm512_cvtepi32_epi8(_mm512_permutexvar_epi32(order, all)));
  }
  if (x < width) scalarKernels().censusCostRow(left + x, right + x, width - x, d, cost + x);
}

void sadCostRow(const std::uint8_t* left, const std::uint8_t* right, int width, int d,
                std::uint8_t* cost) {
  const std::uint8_t* r = right - d;
  int x = 0;
  for (; x + 64 <= width; x += 64) {
    const __m512i a = _mm512_loadu_si512(left + x);
    const __m512i b = _mm512_loadu_si512(r + x);
    _mm512_storeu_si512(cost + x, _mm512_or_si512(_mm512_subs_epu8(a, b), _mm512_subs_epu8(b, a)));
  }
  if (x < width) scalarKernels().sadCostRow(left + x, right + x, width - x, d, cost + x);
}

void addSubRow(std::uint16_t* acc, const std::uint8_t* add, const std::uint8_t* sub,
               std::size_t n) {
  const auto step = [&](std::size_t j, __mmask32 m) {
    __m512i v = _mm512_add_epi16(_mm512_maskz_loadu_epi16(m, acc + j),
                                 _mm512_cvtepu8_epi16(_mm256_maskz_loadu_epi8(m, add + j)));
    if (sub != nullptr)
      v = _mm512_sub_epi16(v, _mm512_cvtepu8_epi16(_mm256_maskz_loadu_epi8(m, sub + j)));
    _mm512_mask_storeu_epi16(acc + j, m, v);
  };
  std::size_t j = 0;
  for (; j + 32 <= n; j += 32) step(j, ~__mmask32{0});  // unmasked body, masked ragged end
  if (j < n) step(j, tailMask32(static_cast<int>(n - j)));
}

// 256-bit loads: a misaligned 512-bit load always splits across two cache lines, a 256-bit one
// only every other time, and the sum is load-bound.
void boxRowDirect(const std::uint16_t* in, int width, int win_w, std::uint16_t* out) {
  int x = 0;
  for (; x + 32 <= width; x += 32) {
    __m256i s0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(in + x));
    __m256i s1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(in + x + 16));
    for (int k = 1; k < win_w; ++k) {
      s0 = _mm256_add_epi16(s0, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(in + x + k)));
      s1 = _mm256_add_epi16(s1,
                            _mm256_loadu_si256(reinterpret_cast<const __m256i*>(in + x + 16 + k)));
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + x), s0);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + x + 16), s1);
  }
  if (x < width) scalarKernels().boxRow(in + x, width - x, win_w, out + x);
}

// A window of 3 q columns (q = 2 .. 11) as q sums of 3: t[j] = in[j] + in[j + 1] + in[j + 2],
// then out[x] = t[x] + t[x + 3] + ... + t[x + 3 (q - 1)] (the same sums mod 2^16, in another
// order). The shifted vectors are made in registers by two-source word permutes rather than
// loaded from shifted addresses (misaligned 512-bit loads split cache lines, and the box is
// load-bound that way): per 32 outputs one load, 2 + (q - 1) permutes, q + 1 adds and one store.
// t0, t1 hold t of columns [x, x + 64). The input is read at [0, width + 3q - 1) only (masked
// past it), the ragged end of the output is masked.
template <int Q>
void boxRowPermute(const std::uint16_t* in, int width, std::uint16_t* out) {
  static_assert(Q >= 2 && 3 * (Q - 1) < 32, "shifts must stay within two vectors");
  const int readable = width + 3 * Q - 1;
  // sh[k]: lane j takes word j + k of the pair (a, b) (indices 32 .. 63 select from b).
  static constexpr auto kIota = [] {
    std::array<std::uint16_t, 64> v{};
    for (int j = 0; j < 64; ++j) v[static_cast<std::size_t>(j)] = static_cast<std::uint16_t>(j);
    return v;
  }();
  __m512i sh[3 * Q];
  for (int k = 1; k < 3 * Q; ++k) sh[k] = _mm512_loadu_si512(kIota.data() + k);
  const auto load = [&](int j) {
    return _mm512_maskz_loadu_epi16(tailMask32(readable - j), in + j);
  };
  const auto threes = [&](__m512i a, __m512i b) {  // t[j] = c[j] + c[j + 1] + c[j + 2]
    return _mm512_add_epi16(_mm512_add_epi16(a, _mm512_permutex2var_epi16(a, sh[1], b)),
                            _mm512_permutex2var_epi16(a, sh[2], b));
  };
  __m512i b = load(32);
  __m512i t0 = threes(load(0), b);
  for (int x = 0; x < width; x += 32) {
    const __m512i c = load(x + 64);
    const __m512i t1 = threes(b, c);
    __m512i acc = t0;
#pragma GCC unroll 11
    for (int k = 1; k < Q; ++k)
      acc = _mm512_add_epi16(acc, _mm512_permutex2var_epi16(t0, sh[3 * k], t1));
    _mm512_mask_storeu_epi16(out + x, tailMask32(width - x), acc);
    t0 = t1;
    b = c;
  }
}

using BoxFn = void (*)(const std::uint16_t*, int, std::uint16_t*);
constexpr BoxFn kBoxPermuteFns[10] = {&boxRowPermute<2>, &boxRowPermute<3>, &boxRowPermute<4>,
                                      &boxRowPermute<5>, &boxRowPermute<6>, &boxRowPermute<7>,
                                      &boxRowPermute<8>, &boxRowPermute<9>, &boxRowPermute<10>,
                                      &boxRowPermute<11>};

void boxRow(const std::uint16_t* in, int width, int win_w, std::uint16_t* out) {
  if (win_w >= 6 && win_w <= 33 && win_w % 3 == 0)
    return kBoxPermuteFns[win_w / 3 - 2](in, width, out);
  boxRowDirect(in, width, win_w, out);
}

// Winner-take-all, the AVX2 kernels' scheme on 32 lanes (stereo_kernels_avx2_wta.cpp): the left
// state of 32 columns stays in registers across the planes, cm / cp are left to wtaNeighbours;
// with bidx1 = bidx + 1 and vi = i:
//   lt = c < best; adj = (bidx1 == vi) on the old bidx
//   second = lt ? pm2 : (adj ? second : min(second, c)); bidx1 = lt ? i + 1 : bidx1
// Two planes per iteration, so the rotation pm2 <- pm1 needs no register copies.
inline void wtaLeftBlock512(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0,
                            std::uint16_t* best_p, std::int16_t* bidx_p, std::uint16_t* second_p,
                            std::uint16_t* pm1_p, std::uint16_t* pm2_p) {
  const __m512i one = _mm512_set1_epi16(1);
  __m512i best = _mm512_loadu_si512(best_p);
  __m512i second = _mm512_loadu_si512(second_p);
  __m512i pm1 = _mm512_loadu_si512(pm1_p);
  __m512i pm2 = _mm512_loadu_si512(pm2_p);
  __m512i bidx1 = _mm512_add_epi16(_mm512_loadu_si512(bidx_p), one);
  __m512i vi = _mm512_set1_epi16(static_cast<short>(i0));
  const auto step = [&](__m512i c) {
    const __m512i vn = _mm512_add_epi16(vi, one);
    const __mmask32 lt = _mm512_cmplt_epu16_mask(c, best);
    const __mmask32 nadj = _mm512_cmpneq_epi16_mask(bidx1, vi);
    second = _mm512_mask_mov_epi16(_mm512_mask_min_epu16(second, nadj, second, c), lt, pm2);
    bidx1 = _mm512_mask_mov_epi16(bidx1, lt, vn);
    best = _mm512_min_epu16(best, c);
    pm2 = pm1;
    pm1 = _mm512_min_epu16(pm1, c);
    vi = vn;
  };
  const std::uint16_t* a = agg;
  int p = 0;
  for (; p + 2 <= n_planes; p += 2, a += 2 * stride) {
    step(_mm512_loadu_si512(a));
    step(_mm512_loadu_si512(a + stride));
  }
  if (p < n_planes) step(_mm512_loadu_si512(a));
  _mm512_storeu_si512(best_p, best);
  _mm512_storeu_si512(second_p, second);
  _mm512_storeu_si512(pm1_p, pm1);
  _mm512_storeu_si512(pm2_p, pm2);
  _mm512_storeu_si512(bidx_p, _mm512_sub_epi16(bidx1, one));
}

void wtaUpdateRows(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0, int width,
                   int d0, const WtaRowState& s) {
  if (n_planes <= 0) return;
  int x = 0;
  for (; x + 32 <= width; x += 32)
    wtaLeftBlock512(agg + x, stride, n_planes, i0, s.best + x, s.bidx + x, s.second + x, s.pm1 + x,
                    s.pm2 + x);
  if (x < width) wtaLeftTail(agg, stride, n_planes, i0, x, width, s);
  // Right image: plane i's candidate for right pixel xr is agg_i[xr + d0 + i]; strictly smaller
  // wins. Right pixels [0, n_right(p)), n_right(p) = width - d0 - i0 - p; 32 of them keep
  // best_r / idx_r in registers across the block's planes, lanes past a plane's end masked.
  const int n_right0 = width - d0 - i0;
  const __m512i one = _mm512_set1_epi16(1);
  for (int xr = 0; xr < n_right0; xr += 32) {
    const __mmask32 m_blk = tailMask32(n_right0 - xr);
    __m512i br = _mm512_maskz_loadu_epi16(m_blk, s.best_r + xr);
    __m512i ir = _mm512_maskz_loadu_epi16(m_blk, s.idx_r + xr);
    __m512i vi = _mm512_set1_epi16(static_cast<short>(i0));
    const std::uint16_t* a = agg + d0 + i0 + xr;
    if (xr + 32 + n_planes - 1 <= n_right0) {  // every lane in every plane
      const auto step = [&](const std::uint16_t* q) {
        const __m512i c = _mm512_loadu_si512(q);
        ir = _mm512_mask_mov_epi16(ir, _mm512_cmplt_epu16_mask(c, br), vi);
        br = _mm512_min_epu16(br, c);
        vi = _mm512_add_epi16(vi, one);
      };
      int p = 0;
      for (; p + 2 <= n_planes; p += 2, a += 2 * (stride + 1)) {
        step(a);
        step(a + stride + 1);
      }
      if (p < n_planes) step(a);
    } else {
      for (int p = 0; p < n_planes; ++p, a += stride + 1) {
        const __mmask32 m = tailMask32(n_right0 - p - xr);
        const __m512i c = _mm512_maskz_loadu_epi16(m, a);
        const __mmask32 upd = _mm512_mask_cmplt_epu16_mask(m, c, br);
        br = _mm512_mask_mov_epi16(br, upd, c);
        ir = _mm512_mask_mov_epi16(ir, upd, vi);
        vi = _mm512_add_epi16(vi, one);
      }
    }
    _mm512_mask_storeu_epi16(s.best_r + xr, m_blk, br);
    _mm512_mask_storeu_epi16(s.idx_r + xr, m_blk, ir);
  }
}

}  // namespace

const StereoKernels& avx512Kernels() {
  static const StereoKernels k{
      Backend::kAvx512,  "avx512",          censusRow,       censusCostRow,
      sadCostRow,        addSubRow,         boxRow,          wtaUpdateRows,
      wtaNeighboursAvx2, finalizeRowAvx512, censusPlanesRow, censusPlanesCostRows};
  return k;
}

}  // namespace svslam::simd

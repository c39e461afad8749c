// AVX-512 (F, BW, VL, VPOPCNTDQ) backend of the stereo row kernels. Compiled with its own
// instruction-set flags and selected at run time; bit-exact with stereo_kernels_scalar.cpp.
// Vector bodies work on 32 x uint16 or 64 x uint8 columns; every kernel is independent per
// column, so the tails are handed to the scalar reference at an offset.
#include <immintrin.h>

#include "simd/stereo_kernels.hpp"

namespace svslam::simd {
namespace {

// 8 byte planes (plane j = census bits 8j..8j+7, MSB first) -> 64 census words at out[0..64).
// Word byte 7 - j (little endian) is plane j.
inline void transposeStore(const __m512i p[8], std::uint64_t* out) {
  const __m512i t0 = _mm512_unpacklo_epi8(p[7], p[6]);
  const __m512i t1 = _mm512_unpackhi_epi8(p[7], p[6]);
  const __m512i t2 = _mm512_unpacklo_epi8(p[5], p[4]);
  const __m512i t3 = _mm512_unpackhi_epi8(p[5], p[4]);
  const __m512i t4 = _mm512_unpacklo_epi8(p[3], p[2]);
  const __m512i t5 = _mm512_unpackhi_epi8(p[3], p[2]);
  const __m512i t6 = _mm512_unpacklo_epi8(p[1], p[0]);
  const __m512i t7 = _mm512_unpackhi_epi8(p[1], p[0]);
  const __m512i u0 = _mm512_unpacklo_epi16(t0, t2);  // pixels 0..3 of each 128-bit lane
  const __m512i u1 = _mm512_unpackhi_epi16(t0, t2);  // 4..7
  const __m512i u2 = _mm512_unpacklo_epi16(t1, t3);  // 8..11
  const __m512i u3 = _mm512_unpackhi_epi16(t1, t3);  // 12..15
  const __m512i u4 = _mm512_unpacklo_epi16(t4, t6);
  const __m512i u5 = _mm512_unpackhi_epi16(t4, t6);
  const __m512i u6 = _mm512_unpacklo_epi16(t5, t7);
  const __m512i u7 = _mm512_unpackhi_epi16(t5, t7);
  __m512i w[8];
  w[0] = _mm512_unpacklo_epi32(u0, u4);  // pixels 0,1 of each lane
  w[1] = _mm512_unpackhi_epi32(u0, u4);  // 2,3
  w[2] = _mm512_unpacklo_epi32(u1, u5);  // 4,5
  w[3] = _mm512_unpackhi_epi32(u1, u5);  // 6,7
  w[4] = _mm512_unpacklo_epi32(u2, u6);  // 8,9
  w[5] = _mm512_unpackhi_epi32(u2, u6);  // 10,11
  w[6] = _mm512_unpacklo_epi32(u3, u7);  // 12,13
  w[7] = _mm512_unpackhi_epi32(u3, u7);  // 14,15
  // Lane L of w[m] holds pixels 16 L + 2 m, 16 L + 2 m + 1: gather lanes into pixel order.
  for (int h = 0; h < 2; ++h) {  // h = 0: pixels 0..7 of each lane; h = 1: pixels 8..15
    const __m512i* q = w + 4 * h;
    const __m512i a_lo = _mm512_shuffle_i64x2(q[0], q[1], _MM_SHUFFLE(1, 0, 1, 0));
    const __m512i b_lo = _mm512_shuffle_i64x2(q[2], q[3], _MM_SHUFFLE(1, 0, 1, 0));
    const __m512i a_hi = _mm512_shuffle_i64x2(q[0], q[1], _MM_SHUFFLE(3, 2, 3, 2));
    const __m512i b_hi = _mm512_shuffle_i64x2(q[2], q[3], _MM_SHUFFLE(3, 2, 3, 2));
    _mm512_storeu_si512(out + 0 + 8 * h, _mm512_shuffle_i64x2(a_lo, b_lo, _MM_SHUFFLE(2, 0, 2, 0)));
    _mm512_storeu_si512(out + 16 + 8 * h, _mm512_shuffle_i64x2(a_lo, b_lo, _MM_SHUFFLE(3, 1, 3, 1)));
    _mm512_storeu_si512(out + 32 + 8 * h, _mm512_shuffle_i64x2(a_hi, b_hi, _MM_SHUFFLE(2, 0, 2, 0)));
    _mm512_storeu_si512(out + 48 + 8 * h, _mm512_shuffle_i64x2(a_hi, b_hi, _MM_SHUFFLE(3, 1, 3, 1)));
  }
}

void censusRow(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w, int win_h,
               std::uint64_t* out) {
  const int cx = win_w / 2;
  const int cy = win_h / 2;
  const int n_off = win_w * win_h - 1;
  const __m512i one = _mm512_set1_epi8(1);
  int x = 0;
  for (; x + 64 <= width; x += 64) {
    const __m512i c = _mm512_loadu_si512(win + cy * stride + cx + x);
    __m512i planes[8];
    for (auto& pl : planes) pl = _mm512_setzero_si512();
    int k = 0;
    for (int dy = 0; dy < win_h; ++dy) {
      const std::uint8_t* r = win + dy * stride + x;
      for (int dx = 0; dx < win_w; ++dx) {
        if (dy == cy && dx == cx) continue;
        const __mmask64 m = _mm512_cmplt_epu8_mask(_mm512_loadu_si512(r + dx), c);
        __m512i& pl = planes[k >> 3];
        pl = _mm512_add_epi8(pl, pl);
        pl = _mm512_mask_add_epi8(pl, m, pl, one);
        ++k;
      }
    }
    // A partial last plane still puts offset k at bit 63 - k: shift it up to the MSB.
    if (n_off % 8 != 0) {
      __m512i& pl = planes[n_off >> 3];
      for (int s = n_off % 8; s < 8; ++s) pl = _mm512_add_epi8(pl, pl);
    }
    transposeStore(planes, out + x);
  }
  if (x < width) scalarKernels().censusRow(win + x, stride, width - x, win_w, win_h, out + x);
}

void censusCostRow(const std::uint64_t* left, const std::uint64_t* right, int width, int d0,
                   int num_disp, std::uint16_t* cost, std::ptrdiff_t cost_stride) {
  for (int i = 0; i < num_disp; ++i) {
    const std::uint64_t* r = right - (d0 + i);
    std::uint16_t* c = cost + i * cost_stride;
    int x = 0;
    for (; x + 16 <= width; x += 16) {
      const __m512i a = _mm512_popcnt_epi64(
          _mm512_xor_si512(_mm512_loadu_si512(left + x), _mm512_loadu_si512(r + x)));
      const __m512i b = _mm512_popcnt_epi64(
          _mm512_xor_si512(_mm512_loadu_si512(left + x + 8), _mm512_loadu_si512(r + x + 8)));
      const __m256i packed = _mm256_inserti128_si256(
          _mm256_castsi128_si256(_mm512_cvtepi64_epi16(a)), _mm512_cvtepi64_epi16(b), 1);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(c + x), packed);
    }
    if (x < width) scalarKernels().censusCostRow(left + x, right + x, width - x, d0 + i, 1, c + x, cost_stride);
  }
}

void sadCostRow(const std::uint8_t* left, const std::uint8_t* right, int width, int d0,
                int num_disp, std::uint16_t* cost, std::ptrdiff_t cost_stride) {
  for (int i = 0; i < num_disp; ++i) {
    const std::uint8_t* r = right - (d0 + i);
    std::uint16_t* c = cost + i * cost_stride;
    int x = 0;
    for (; x + 32 <= width; x += 32) {
      const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(left + x));
      const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(r + x));
      const __m256i ad = _mm256_or_si256(_mm256_subs_epu8(a, b), _mm256_subs_epu8(b, a));
      _mm512_storeu_si512(c + x, _mm512_cvtepu8_epi16(ad));
    }
    if (x < width) scalarKernels().sadCostRow(left + x, right + x, width - x, d0 + i, 1, c + x, cost_stride);
  }
}

void addSubRow(std::uint16_t* acc, const std::uint16_t* add, const std::uint16_t* sub, std::size_t n) {
  std::size_t j = 0;
  if (sub == nullptr) {
    for (; j + 32 <= n; j += 32)
      _mm512_storeu_si512(acc + j, _mm512_add_epi16(_mm512_loadu_si512(acc + j), _mm512_loadu_si512(add + j)));
  } else {
    for (; j + 32 <= n; j += 32) {
      const __m512i v = _mm512_add_epi16(_mm512_loadu_si512(acc + j), _mm512_loadu_si512(add + j));
      _mm512_storeu_si512(acc + j, _mm512_sub_epi16(v, _mm512_loadu_si512(sub + j)));
    }
  }
  if (j < n) scalarKernels().addSubRow(acc + j, add + j, sub == nullptr ? nullptr : sub + j, n - j);
}

void boxRow(const std::uint16_t* in, int width, int win_w, std::uint16_t* out) {
  int x = 0;
  for (; x + 32 <= width; x += 32) {
    __m512i s = _mm512_loadu_si512(in + x);
    for (int k = 1; k < win_w; ++k) s = _mm512_add_epi16(s, _mm512_loadu_si512(in + x + k));
    _mm512_storeu_si512(out + x, s);
  }
  if (x < width) scalarKernels().boxRow(in + x, width - x, win_w, out + x);
}

void wtaLeftRow(const std::uint16_t* cost, std::ptrdiff_t stride, int width, int num_disp,
                std::uint16_t* best_cost, std::int16_t* best_idx) {
  int x = 0;
  for (; x + 32 <= width; x += 32) {
    __m512i best = _mm512_set1_epi16(-1);
    __m512i idx = _mm512_set1_epi16(-1);
    for (int i = 0; i < num_disp; ++i) {
      const __m512i c = _mm512_loadu_si512(cost + i * stride + x);
      const __mmask32 m = _mm512_cmplt_epu16_mask(c, best);
      best = _mm512_mask_mov_epi16(best, m, c);
      idx = _mm512_mask_mov_epi16(idx, m, _mm512_set1_epi16(static_cast<short>(i)));
    }
    _mm512_storeu_si512(best_cost + x, best);
    _mm512_storeu_si512(best_idx + x, idx);
  }
  if (x < width) scalarKernels().wtaLeftRow(cost + x, stride, width - x, num_disp, best_cost + x, best_idx + x);
}

void secondBestRow(const std::uint16_t* cost, std::ptrdiff_t stride, int width, int num_disp,
                   const std::int16_t* best_idx, std::uint16_t* second) {
  int x = 0;
  const __m512i one = _mm512_set1_epi16(1);
  for (; x + 32 <= width; x += 32) {
    const __m512i idx = _mm512_loadu_si512(best_idx + x);
    __m512i sec = _mm512_set1_epi16(-1);
    for (int i = 0; i < num_disp; ++i) {
      const __m512i c = _mm512_loadu_si512(cost + i * stride + x);
      const __m512i dist = _mm512_abs_epi16(_mm512_sub_epi16(_mm512_set1_epi16(static_cast<short>(i)), idx));
      const __mmask32 far = _mm512_cmpgt_epi16_mask(dist, one);
      const __mmask32 m = _mm512_mask_cmplt_epu16_mask(far, c, sec);
      sec = _mm512_mask_mov_epi16(sec, m, c);
    }
    _mm512_storeu_si512(second + x, sec);
  }
  if (x < width) scalarKernels().secondBestRow(cost + x, stride, width - x, num_disp, best_idx + x, second + x);
}

void wtaRightRow(const std::uint16_t* cost, std::ptrdiff_t stride, int width, int d0, int num_disp,
                 std::int16_t* best_idx_r) {
  int xr = 0;
  for (; xr + 32 <= width; xr += 32) {
    __m512i best = _mm512_set1_epi16(-1);
    __m512i idx = _mm512_set1_epi16(-1);
    for (int i = 0; i < num_disp; ++i) {
      const __m512i c = _mm512_loadu_si512(cost + i * stride + xr + d0 + i);
      const __mmask32 m = _mm512_cmplt_epu16_mask(c, best);
      best = _mm512_mask_mov_epi16(best, m, c);
      idx = _mm512_mask_mov_epi16(idx, m, _mm512_set1_epi16(static_cast<short>(i)));
    }
    _mm512_storeu_si512(best_idx_r + xr, idx);
  }
  if (xr < width) scalarKernels().wtaRightRow(cost + xr, stride, width - xr, d0, num_disp, best_idx_r + xr);
}

}  // namespace

const StereoKernels& avx512Kernels() {
  static const StereoKernels k{Backend::kAvx512, "avx512", censusRow,  censusCostRow,
                               sadCostRow,        addSubRow, boxRow,    wtaLeftRow,
                               secondBestRow,     wtaRightRow};
  return k;
}

}  // namespace svslam::simd

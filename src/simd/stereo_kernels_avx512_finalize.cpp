// AVX-512 finalizeRow of the stereo kernels: the per-pixel steps of the reference
// finalizeRange (uniqueness, texture, left-right check, sub-pixel, sigma) in 16 float lanes,
// the AVX2 kernel's arithmetic with mask registers for the tests. Bit-exact with
// stereo_kernels_scalar.cpp (the same float operations, lane by lane).
#include <immintrin.h>

#include <limits>

#include "simd/stereo_kernels.hpp"

namespace svslam::simd {

// 16 pixels per step in 32-bit lanes; each test of finalizeRange is a lane mask and the counts
// are population counts of the masks. The ragged end goes to the scalar reference.
void finalizeRowAvx512(const WtaRowState& s, const std::uint8_t* low_texture, int width,
                       const FinalizeParams& p, float* disp, float* sigma, float* curv,
                       FinalizeCounts& counts) {
  const __m512i zero = _mm512_setzero_si512();
  const __m512i u16max = _mm512_set1_epi32(0xFFFF);
  const __m512i lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512i vd0 = _mm512_set1_epi32(p.d0);
  const __m512i last_idx = _mm512_set1_epi32(p.num_disp - 1);
  const __m512i wmax = _mm512_set1_epi32(width - 1);
  const __m512i lr_max = _mm512_set1_epi32(p.lr_max_diff);
  const __m512i max_denom = _mm512_set1_epi32(p.max_denom);
  const __m512i uniq_factor = _mm512_set1_epi32(100 + p.uniqueness_pct);
  const __m512i hundred = _mm512_set1_epi32(100);
  const __m512 inf = _mm512_set1_ps(std::numeric_limits<float>::infinity());
  const __m512 inv_area = _mm512_set1_ps(p.inv_area);
  const __mmask16 use_uniq = p.uniqueness_pct > 0 ? 0xFFFF : 0;
  const __mmask16 use_lr = p.lr_check ? 0xFFFF : 0;
  const __mmask16 use_sub = p.subpixel ? 0xFFFF : 0;
  const auto load16 = [](const void* q) {
    return _mm256_loadu_si256(static_cast<const __m256i*>(q));
  };
  int x = 0;
  for (; x + 16 <= width; x += 16) {
    const __m512i idx = _mm512_cvtepi16_epi32(load16(s.bidx + x));
    const __m512i best = _mm512_cvtepu16_epi32(load16(s.best + x));
    const __m512i second = _mm512_cvtepu16_epi32(load16(s.second + x));
    const __m512i cm = _mm512_cvtepu16_epi32(load16(s.cm + x));
    const __m512i cp = _mm512_cvtepu16_epi32(load16(s.cp + x));
    const __mmask16 no_cand = _mm512_cmplt_epi32_mask(idx, zero);
    __mmask16 low_tex = 0;
    if (low_texture != nullptr)
      low_tex = _mm_test_epi8_mask(
          _mm_loadu_si128(reinterpret_cast<const __m128i*>(low_texture + x)), _mm_set1_epi8(-1));
    // 100 second and (100 + u) best are below 2^31, so signed compares order them.
    const __mmask16 no_margin = _mm512_cmple_epi32_mask(_mm512_mullo_epi32(second, hundred),
                                                        _mm512_mullo_epi32(best, uniq_factor));
    const __mmask16 not_unique = use_uniq & (_mm512_cmpeq_epi32_mask(second, u16max) | no_margin);
    const __m512i vx = _mm512_add_epi32(_mm512_set1_epi32(x), lanes);
    const __m512i xr = _mm512_min_epi32(
        _mm512_max_epi32(_mm512_sub_epi32(vx, _mm512_add_epi32(vd0, idx)), zero), wmax);
    // 32-bit gather at idx_r + xr (2-byte scale): the low half is idx_r[xr].
    const __m512i g = _mm512_i32gather_epi32(xr, s.idx_r, 2);
    const __m512i idr = _mm512_srai_epi32(_mm512_slli_epi32(g, 16), 16);
    const __mmask16 lr_bad =
        use_lr & (_mm512_cmplt_epi32_mask(idr, zero) |
                  _mm512_cmpgt_epi32_mask(_mm512_abs_epi32(_mm512_sub_epi32(idr, idx)), lr_max));
    // First failing test wins.
    const __mmask16 f2 = low_tex & ~no_cand;
    const __mmask16 any12 = no_cand | low_tex;
    const __mmask16 f3 = not_unique & ~any12;
    const __mmask16 any123 = any12 | not_unique;
    const __mmask16 f4 = lr_bad & ~any123;
    const __mmask16 invalid = any123 | lr_bad;
    counts.no_candidate += __builtin_popcount(no_cand);
    counts.low_texture += __builtin_popcount(f2);
    counts.not_unique += __builtin_popcount(f3);
    counts.lr_inconsistent += __builtin_popcount(f4);
    counts.valid += 16 - __builtin_popcount(invalid);

    const __m512i denom = _mm512_sub_epi32(_mm512_add_epi32(cm, cp), _mm512_add_epi32(best, best));
    const __mmask16 parabola =
        _mm512_cmpgt_epi32_mask(idx, zero) & _mm512_cmplt_epi32_mask(idx, last_idx) &
        _mm512_cmpneq_epi32_mask(cp, u16max) & _mm512_cmpgt_epi32_mask(denom, zero);
    const __m512i safe_denom = _mm512_mask_mov_epi32(_mm512_set1_epi32(1), parabola, denom);
    const __m512 q = _mm512_div_ps(_mm512_cvtepi32_ps(_mm512_sub_epi32(cm, cp)),
                                   _mm512_cvtepi32_ps(_mm512_add_epi32(safe_denom, safe_denom)));
    const __m512 delta = _mm512_maskz_mov_ps(parabola & use_sub, q);  // +0 where not used
    const __m512 d = _mm512_add_ps(_mm512_cvtepi32_ps(_mm512_add_epi32(vd0, idx)), delta);
    const __m512i tab_i = _mm512_maskz_mov_epi32(parabola, _mm512_min_epi32(denom, max_denom));
    const __m512 sg = _mm512_i32gather_ps(tab_i, p.sigma_by_denom, 4);
    const __m512 cv =
        _mm512_maskz_mov_ps(parabola, _mm512_mul_ps(_mm512_cvtepi32_ps(denom), inv_area));
    _mm512_storeu_ps(disp + x, _mm512_mask_mov_ps(d, invalid, inf));
    _mm512_storeu_ps(sigma + x, _mm512_mask_mov_ps(sg, invalid, inf));
    _mm512_storeu_ps(curv + x, _mm512_mask_mov_ps(cv, invalid, inf));
  }
  if (x < width) finalizeRange(s, low_texture, x, width, p, disp, sigma, curv, counts);
}

}  // namespace svslam::simd

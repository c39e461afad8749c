// AVX2 finalizeRow of the stereo kernels: the per-pixel steps of
// the reference finalizeRange (uniqueness, texture, left-right check, sub-pixel, sigma) in 8
// float lanes. Bit-exact with stereo_kernels_scalar.cpp.
#include <immintrin.h>

#include <cstdlib>
#include <limits>

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

}  // namespace svslam::simd

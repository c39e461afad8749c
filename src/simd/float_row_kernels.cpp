// Float row kernels: the portable reference (auto-vectorised for the build's baseline); on
// x86-64 the same operations in AVX2 (target attribute, no FMA), chosen at run time; on AArch64
// in NEON.
#include "simd/float_row_kernels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#if defined(__x86_64__)
#include <immintrin.h>
#elif defined(__aarch64__)
#include <arm_neon.h>
#endif

namespace svslam::simd {
namespace {

void axpyScalar(float* __restrict__ t, const float* __restrict__ p, float c, int n) {
  for (int x = 0; x < n; ++x) t[x] += c * p[x];
}

void convolveScalar(const float* const* rows, const float* c, int taps, float* __restrict__ out,
                    int n) {
  for (int x = 0; x < n; ++x) out[x] = 0.0f;
  for (int k = 0; k < taps; ++k) axpyScalar(out, rows[k], c[k], n);
}

void productsScalar(const float* __restrict__ gx, const float* __restrict__ gy,
                    float* __restrict__ xx, float* __restrict__ yy, float* __restrict__ xy, int n) {
  for (int x = 0; x < n; ++x) {
    xx[x] = gx[x] * gx[x];
    yy[x] = gy[x] * gy[x];
    xy[x] = gx[x] * gy[x];
  }
}

float responseScalar(const float* ra, const float* rb, const float* rc, bool harris, double k,
                     float* rr, int n, float max_r) {
  for (int x = 0; x < n; ++x) {
    const double a = ra[x], b = rb[x], c = rc[x];
    const double r = harris ? a * c - b * b - k * (a + c) * (a + c)
                            : 0.5 * (a + c) - std::sqrt(0.25 * (a - c) * (a - c) + b * b);
    rr[x] = static_cast<float>(r);
    max_r = std::max(max_r, rr[x]);
  }
  return max_r;
}

int localMaximaScalar(const float* up, const float* mid, const float* down, float thr, int x0,
                      int x1, int* xs) {
  int count = 0;
  for (int x = x0; x < x1; ++x) {
    const float r = mid[x];
    if (r > thr && r > up[x - 1] && r > up[x] && r > up[x + 1] && r > mid[x - 1] &&
        r >= mid[x + 1] && r >= down[x - 1] && r >= down[x] && r >= down[x + 1])
      xs[count++] = x;
  }
  return count;
}

#if defined(__x86_64__)
#define SVSLAM_FLOAT_ROW_AVX2 1
// "avx2" does not enable FMA: each product is rounded before the add, as in the reference.
// Outputs held in registers over all taps: the rows are read once and out is written once (the
// reference reads and writes out once per tap); same operations per element. Each output's adds
// form a chain of `taps` dependent adds (3-4 cycles each), so B independent vectors of 8 run
// together to hide that latency: B = 8 (64 outputs) in the body, then 2, then 1, then scalar.
template <int B>
__attribute__((target("avx2"), always_inline)) inline void convolveBlockAvx2(
    const float* const* rows, const float* c, int taps, float* __restrict__ out, int x) {
  __m256 acc[B];
  for (int i = 0; i < B; ++i) acc[i] = _mm256_setzero_ps();
  for (int k = 0; k < taps; ++k) {
    const __m256 ck = _mm256_set1_ps(c[k]);
    const float* r = rows[k] + x;
    for (int i = 0; i < B; ++i)
      acc[i] = _mm256_add_ps(acc[i], _mm256_mul_ps(ck, _mm256_loadu_ps(r + 8 * i)));
  }
  for (int i = 0; i < B; ++i) _mm256_storeu_ps(out + x + 8 * i, acc[i]);
}

__attribute__((target("avx2"))) void convolveAvx2(const float* const* rows, const float* c,
                                                  int taps, float* __restrict__ out, int n) {
  int x = 0;
  for (; x + 64 <= n; x += 64) convolveBlockAvx2<8>(rows, c, taps, out, x);
  for (; x + 16 <= n; x += 16) convolveBlockAvx2<2>(rows, c, taps, out, x);
  for (; x + 8 <= n; x += 8) convolveBlockAvx2<1>(rows, c, taps, out, x);
  for (; x < n; ++x) {
    float a = 0.0f;
    for (int k = 0; k < taps; ++k) a += c[k] * rows[k][x];
    out[x] = a;
  }
}

__attribute__((target("avx2"))) void productsAvx2(const float* __restrict__ gx,
                                                  const float* __restrict__ gy,
                                                  float* __restrict__ xx, float* __restrict__ yy,
                                                  float* __restrict__ xy, int n) {
  for (int x = 0; x < n; ++x) {
    xx[x] = gx[x] * gx[x];
    yy[x] = gy[x] * gy[x];
    xy[x] = gx[x] * gy[x];
  }
}

// Four pixels per step in double lanes, the same operations as the reference; the running
// maximum is exact in any order (max(acc, v) keeps acc when v is NaN, as std::max does).
__attribute__((target("avx2"))) float responseAvx2(const float* ra, const float* rb,
                                                   const float* rc, bool harris, double k,
                                                   float* rr, int n, float max_r) {
  int x = 0;
  __m128 vmax = _mm_set1_ps(max_r);
  const __m256d vk = _mm256_set1_pd(k), half = _mm256_set1_pd(0.5), quarter = _mm256_set1_pd(0.25);
  for (; x + 4 <= n; x += 4) {
    const __m256d a = _mm256_cvtps_pd(_mm_loadu_ps(ra + x)), b = _mm256_cvtps_pd(_mm_loadu_ps(rb + x)),
                  c = _mm256_cvtps_pd(_mm_loadu_ps(rc + x));
    __m256d r;
    if (harris) {
      const __m256d s = _mm256_add_pd(a, c);
      r = _mm256_sub_pd(_mm256_sub_pd(_mm256_mul_pd(a, c), _mm256_mul_pd(b, b)),
                        _mm256_mul_pd(_mm256_mul_pd(vk, s), s));
    } else {
      const __m256d d = _mm256_sub_pd(a, c);
      const __m256d q = _mm256_add_pd(_mm256_mul_pd(_mm256_mul_pd(quarter, d), d), _mm256_mul_pd(b, b));
      r = _mm256_sub_pd(_mm256_mul_pd(half, _mm256_add_pd(a, c)), _mm256_sqrt_pd(q));
    }
    const __m128 rf = _mm256_cvtpd_ps(r);
    _mm_storeu_ps(rr + x, rf);
    vmax = _mm_max_ps(rf, vmax);  // second operand when either is NaN
  }
  alignas(16) float m[4];
  _mm_store_ps(m, vmax);
  for (const float v : m) max_r = std::max(max_r, v);
  return responseScalar(ra + x, rb + x, rc + x, harris, k, rr + x, n - x, max_r);
}

// Eight candidates per step: nine ordered compares and a bit scan of the mask.
__attribute__((target("avx2"))) int localMaximaAvx2(const float* up, const float* mid,
                                                        const float* down, float thr, int x0,
                                                        int x1, int* xs) {
  int count = 0;
  int x = x0;
  const __m256 vt = _mm256_set1_ps(thr);
  for (; x + 8 <= x1; x += 8) {
    const __m256 r = _mm256_loadu_ps(mid + x);
    __m256 m = _mm256_cmp_ps(r, vt, _CMP_GT_OQ);
    if (_mm256_testz_ps(m, m)) continue;  // all below the threshold
    m = _mm256_and_ps(m, _mm256_cmp_ps(r, _mm256_loadu_ps(up + x - 1), _CMP_GT_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(r, _mm256_loadu_ps(up + x), _CMP_GT_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(r, _mm256_loadu_ps(up + x + 1), _CMP_GT_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(r, _mm256_loadu_ps(mid + x - 1), _CMP_GT_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(r, _mm256_loadu_ps(mid + x + 1), _CMP_GE_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(r, _mm256_loadu_ps(down + x - 1), _CMP_GE_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(r, _mm256_loadu_ps(down + x), _CMP_GE_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(r, _mm256_loadu_ps(down + x + 1), _CMP_GE_OQ));
    for (unsigned bits = static_cast<unsigned>(_mm256_movemask_ps(m)); bits != 0;
         bits &= bits - 1)
      xs[count++] = x + __builtin_ctz(bits);
  }
  return count + localMaximaScalar(up, mid, down, thr, x, x1, xs + count);
}
#endif

#if defined(__aarch64__)
#define SVSLAM_FLOAT_ROW_NEON 1
// AArch64 NEON (always present there): separate vmulq/vaddq, never fused (the file is built with
// -ffp-contract=off), so each element sees the reference's operations. Not on 32-bit ARM, whose
// NEON flushes subnormals and has no float64 lanes.
template <int B>
inline void convolveBlockNeon(const float* const* rows, const float* c, int taps,
                              float* __restrict__ out, int x) {
  float32x4_t acc[B];
  for (int i = 0; i < B; ++i) acc[i] = vdupq_n_f32(0.0f);
  for (int k = 0; k < taps; ++k) {
    const float32x4_t ck = vdupq_n_f32(c[k]);
    const float* r = rows[k] + x;
    for (int i = 0; i < B; ++i) acc[i] = vaddq_f32(acc[i], vmulq_f32(ck, vld1q_f32(r + 4 * i)));
  }
  for (int i = 0; i < B; ++i) vst1q_f32(out + x + 4 * i, acc[i]);
}

void convolveNeon(const float* const* rows, const float* c, int taps, float* __restrict__ out,
                  int n) {
  int x = 0;
  for (; x + 32 <= n; x += 32) convolveBlockNeon<8>(rows, c, taps, out, x);
  for (; x + 4 <= n; x += 4) convolveBlockNeon<1>(rows, c, taps, out, x);
  for (; x < n; ++x) {
    float a = 0.0f;
    for (int k = 0; k < taps; ++k) a += c[k] * rows[k][x];
    out[x] = a;
  }
}

// Four pixels per step in two float64x2 halves; running maximum as std::max: v > m ? v : m.
float responseNeon(const float* ra, const float* rb, const float* rc, bool harris, double k,
                   float* rr, int n, float max_r) {
  int x = 0;
  float32x4_t vmax = vdupq_n_f32(max_r);
  const float64x2_t vk = vdupq_n_f64(k), half = vdupq_n_f64(0.5), quarter = vdupq_n_f64(0.25);
  auto r2 = [&](float64x2_t a, float64x2_t b, float64x2_t c) {
    if (harris) {
      const float64x2_t s = vaddq_f64(a, c);
      return vsubq_f64(vsubq_f64(vmulq_f64(a, c), vmulq_f64(b, b)), vmulq_f64(vmulq_f64(vk, s), s));
    }
    const float64x2_t d = vsubq_f64(a, c);
    const float64x2_t q = vaddq_f64(vmulq_f64(vmulq_f64(quarter, d), d), vmulq_f64(b, b));
    return vsubq_f64(vmulq_f64(half, vaddq_f64(a, c)), vsqrtq_f64(q));
  };
  for (; x + 4 <= n; x += 4) {
    const float32x4_t a = vld1q_f32(ra + x), b = vld1q_f32(rb + x), c = vld1q_f32(rc + x);
    const float64x2_t lo = r2(vcvt_f64_f32(vget_low_f32(a)), vcvt_f64_f32(vget_low_f32(b)),
                              vcvt_f64_f32(vget_low_f32(c)));
    const float64x2_t hi = r2(vcvt_high_f64_f32(a), vcvt_high_f64_f32(b), vcvt_high_f64_f32(c));
    const float32x4_t rf = vcvt_high_f32_f64(vcvt_f32_f64(lo), hi);
    vst1q_f32(rr + x, rf);
    vmax = vbslq_f32(vcgtq_f32(rf, vmax), rf, vmax);
  }
  float m[4];
  vst1q_f32(m, vmax);
  for (const float v : m) max_r = std::max(max_r, v);
  return responseScalar(ra + x, rb + x, rc + x, harris, k, rr + x, n - x, max_r);
}

int localMaximaNeon(const float* up, const float* mid, const float* down, float thr, int x0,
                    int x1, int* xs) {
  int count = 0;
  int x = x0;
  const float32x4_t vt = vdupq_n_f32(thr);
  for (; x + 4 <= x1; x += 4) {
    const float32x4_t r = vld1q_f32(mid + x);
    uint32x4_t m = vcgtq_f32(r, vt);
    if (vmaxvq_u32(m) == 0) continue;  // all below the threshold
    m = vandq_u32(m, vcgtq_f32(r, vld1q_f32(up + x - 1)));
    m = vandq_u32(m, vcgtq_f32(r, vld1q_f32(up + x)));
    m = vandq_u32(m, vcgtq_f32(r, vld1q_f32(up + x + 1)));
    m = vandq_u32(m, vcgtq_f32(r, vld1q_f32(mid + x - 1)));
    m = vandq_u32(m, vcgeq_f32(r, vld1q_f32(mid + x + 1)));
    m = vandq_u32(m, vcgeq_f32(r, vld1q_f32(down + x - 1)));
    m = vandq_u32(m, vcgeq_f32(r, vld1q_f32(down + x)));
    m = vandq_u32(m, vcgeq_f32(r, vld1q_f32(down + x + 1)));
    if (vmaxvq_u32(m) == 0) continue;
    std::uint32_t lanes[4];
    vst1q_u32(lanes, m);
    for (int i = 0; i < 4; ++i)
      if (lanes[i] != 0) xs[count++] = x + i;
  }
  return count + localMaximaScalar(up, mid, down, thr, x, x1, xs + count);
}
#endif

}  // namespace

bool floatRowBackendAvailable(Backend b) {
  if (b == Backend::kAuto || b == Backend::kScalar) return true;
#if defined(SVSLAM_FLOAT_ROW_AVX2)
  if (b == Backend::kAvx2) return __builtin_cpu_supports("avx2");
#endif
#if defined(SVSLAM_FLOAT_ROW_NEON)
  if (b == Backend::kNeon) return true;
#endif
  return false;
}

const FloatRowKernels& floatRowKernels([[maybe_unused]] Backend b) {
  static const FloatRowKernels scalar{Backend::kScalar, "scalar", convolveScalar, productsScalar,
                                        responseScalar, localMaximaScalar};
#if defined(SVSLAM_FLOAT_ROW_AVX2)
  static const FloatRowKernels avx2{Backend::kAvx2, "avx2", convolveAvx2, productsAvx2,
                                      responseAvx2, localMaximaAvx2};
  if ((b == Backend::kAuto || b == Backend::kAvx2) && floatRowBackendAvailable(Backend::kAvx2))
    return avx2;
#endif
#if defined(SVSLAM_FLOAT_ROW_NEON)
  // products: the reference loop, which the compiler vectorises for NEON already.
  static const FloatRowKernels neon{Backend::kNeon, "neon", convolveNeon, productsScalar,
                                      responseNeon, localMaximaNeon};
  if (b == Backend::kAuto || b == Backend::kNeon) return neon;
#endif
  return scalar;
}

}  // namespace svslam::simd

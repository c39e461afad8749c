// Float row kernels: the portable reference (auto-vectorised for the build's baseline) and, on
// x86-64, the same loops compiled for AVX2 (target attribute, no FMA) and chosen at run time.
#include "simd/float_row_kernels.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
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

#if defined(__x86_64__)
#define SVSLAM_FLOAT_ROW_AVX2 1
// "avx2" does not enable FMA: c * p[x] is rounded before the add, as in the reference.
__attribute__((target("avx2"))) void axpyAvx2(float* __restrict__ t, const float* __restrict__ p,
                                              float c, int n) {
  for (int x = 0; x < n; ++x) t[x] += c * p[x];
}

// Eight outputs at a time held in a register over all taps: the rows are read once and out is
// written once (the reference reads and writes out once per tap); same operations per element.
__attribute__((target("avx2"))) void convolveAvx2(const float* const* rows, const float* c,
                                                  int taps, float* __restrict__ out, int n) {
  int x = 0;
  for (; x + 16 <= n; x += 16) {
    __m256 a0 = _mm256_setzero_ps(), a1 = _mm256_setzero_ps();
    for (int k = 0; k < taps; ++k) {
      const __m256 ck = _mm256_set1_ps(c[k]);
      a0 = _mm256_add_ps(a0, _mm256_mul_ps(ck, _mm256_loadu_ps(rows[k] + x)));
      a1 = _mm256_add_ps(a1, _mm256_mul_ps(ck, _mm256_loadu_ps(rows[k] + x + 8)));
    }
    _mm256_storeu_ps(out + x, a0);
    _mm256_storeu_ps(out + x + 8, a1);
  }
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
#endif

}  // namespace

bool floatRowBackendAvailable(Backend b) {
  if (b == Backend::kAuto || b == Backend::kScalar) return true;
#if defined(SVSLAM_FLOAT_ROW_AVX2)
  if (b == Backend::kAvx2) return __builtin_cpu_supports("avx2");
#endif
  return false;
}

const FloatRowKernels& floatRowKernels(Backend b) {
  static const FloatRowKernels scalar{Backend::kScalar, "scalar", axpyScalar, convolveScalar,
                                        productsScalar};
#if defined(SVSLAM_FLOAT_ROW_AVX2)
  static const FloatRowKernels avx2{Backend::kAvx2, "avx2", axpyAvx2, convolveAvx2, productsAvx2};
  if ((b == Backend::kAuto || b == Backend::kAvx2) && floatRowBackendAvailable(Backend::kAvx2))
    return avx2;
#endif
  return scalar;
}

}  // namespace svslam::simd

// AVX2 + FMA3 backend of the matrix kernels (compiled with -mavx2 -mfma; chosen at run time).
#include <immintrin.h>

#include <initializer_list>

#include "simd/matrix_kernels.hpp"
#include "simd/matrix_kernels_tiling.hpp"

namespace svslam::simd {
namespace {

// One 12 x 4 block: twelve 4-double accumulators, per k three loads of A (12 rows) and four
// broadcasts of B. acc <- -(a b) + acc with one rounding (VFNMADD), as std::fma(-a, b, acc).
struct Avx2Micro {
  static constexpr int MR = 12, NR = 4;
  // Not inlined: the driver calls it on P and on a small buffer, and an inlined copy on the buffer
  // would keep the accumulators in memory. Named accumulators (not an array) stay in registers.
  [[gnu::noinline]] static void tile(const double* a, const double* b, int r, double* C,
                                     std::ptrdiff_t ldc) {
    double* c0 = C;
    double* c1 = C + ldc;
    double* c2 = C + 2 * ldc;
    double* c3 = C + 3 * ldc;
    // The block of C is read only after the loop over k: start bringing it in now (12 doubles
    // per column span at most two cache lines).
    for (double* p : {c0, c1, c2, c3}) {
      _mm_prefetch(reinterpret_cast<const char*>(p), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(p + 11), _MM_HINT_T0);
    }
    __m256d c00 = _mm256_setzero_pd(), c01 = _mm256_setzero_pd(), c02 = _mm256_setzero_pd();
    __m256d c10 = _mm256_setzero_pd(), c11 = _mm256_setzero_pd(), c12 = _mm256_setzero_pd();
    __m256d c20 = _mm256_setzero_pd(), c21 = _mm256_setzero_pd(), c22 = _mm256_setzero_pd();
    __m256d c30 = _mm256_setzero_pd(), c31 = _mm256_setzero_pd(), c32 = _mm256_setzero_pd();
    for (int k = 0; k < r; ++k, a += MR, b += NR) {
      const __m256d a0 = _mm256_loadu_pd(a), a1 = _mm256_loadu_pd(a + 4),
                    a2 = _mm256_loadu_pd(a + 8);
      __m256d bu = _mm256_broadcast_sd(b);
      c00 = _mm256_fnmadd_pd(a0, bu, c00);
      c01 = _mm256_fnmadd_pd(a1, bu, c01);
      c02 = _mm256_fnmadd_pd(a2, bu, c02);
      bu = _mm256_broadcast_sd(b + 1);
      c10 = _mm256_fnmadd_pd(a0, bu, c10);
      c11 = _mm256_fnmadd_pd(a1, bu, c11);
      c12 = _mm256_fnmadd_pd(a2, bu, c12);
      bu = _mm256_broadcast_sd(b + 2);
      c20 = _mm256_fnmadd_pd(a0, bu, c20);
      c21 = _mm256_fnmadd_pd(a1, bu, c21);
      c22 = _mm256_fnmadd_pd(a2, bu, c22);
      bu = _mm256_broadcast_sd(b + 3);
      c30 = _mm256_fnmadd_pd(a0, bu, c30);
      c31 = _mm256_fnmadd_pd(a1, bu, c31);
      c32 = _mm256_fnmadd_pd(a2, bu, c32);
    }
    const auto add = [](double* p, __m256d v) {
      _mm256_storeu_pd(p, _mm256_add_pd(_mm256_loadu_pd(p), v));
    };
    add(c0, c00), add(c0 + 4, c01), add(c0 + 8, c02);
    add(c1, c10), add(c1 + 4, c11), add(c1 + 8, c12);
    add(c2, c20), add(c2 + 4, c21), add(c2 + 8, c22);
    add(c3, c30), add(c3 + 4, c31), add(c3 + 8, c32);
  }
};

}  // namespace

const MatrixKernels& avx2MatrixKernels() {
  static const MatrixKernels k{Backend::kAvx2, "avx2", rankUpdateTiled<Avx2Micro>};
  return k;
}

}  // namespace svslam::simd

// AArch64 Advanced SIMD backend of the matrix kernels (float64x2 lanes; chosen at run time).
#include <arm_neon.h>

#include "simd/matrix_kernels.hpp"
#include "simd/matrix_kernels_tiling.hpp"

namespace svslam::simd {
namespace {

// One 8 x 4 block: sixteen 2-double accumulators, per k four loads of A (8 rows) and two of B.
// acc <- acc - a b with one rounding (FMLS), as std::fma(-a, b, acc), from zero; then C + acc.
struct NeonMicro {
  static constexpr int MR = 8, NR = 4;
  // Not inlined: the driver calls it on P and on a small buffer, and an inlined copy on the buffer
  // would keep the accumulators in memory.
  [[gnu::noinline]] static void tile(const double* a, const double* b, int r, double* C,
                                     std::ptrdiff_t ldc) {
    float64x2_t c[NR][4];
    for (int u = 0; u < NR; ++u)
      for (int v = 0; v < 4; ++v) c[u][v] = vdupq_n_f64(0.0);
    for (int k = 0; k < r; ++k, a += MR, b += NR) {
      float64x2_t av[4];
      for (int v = 0; v < 4; ++v) av[v] = vld1q_f64(a + 2 * v);
      const float64x2_t b01 = vld1q_f64(b), b23 = vld1q_f64(b + 2);
      for (int v = 0; v < 4; ++v) {
        c[0][v] = vfmsq_laneq_f64(c[0][v], av[v], b01, 0);
        c[1][v] = vfmsq_laneq_f64(c[1][v], av[v], b01, 1);
        c[2][v] = vfmsq_laneq_f64(c[2][v], av[v], b23, 0);
        c[3][v] = vfmsq_laneq_f64(c[3][v], av[v], b23, 1);
      }
    }
    for (int u = 0; u < NR; ++u)
      for (int v = 0; v < 4; ++v) {
        double* p = C + 2 * v + u * ldc;
        vst1q_f64(p, vaddq_f64(vld1q_f64(p), c[u][v]));  // C + (sum from zero), as the reference
      }
  }
};

}  // namespace

const MatrixKernels& neonMatrixKernels() {
  static const MatrixKernels k{Backend::kNeon, "neon", rankUpdateTiled<NeonMicro>};
  return k;
}

}  // namespace svslam::simd

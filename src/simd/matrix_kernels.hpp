#pragma once
// Dense double-precision kernels of the EKF covariance update, one table per instruction set.
//
// rankUpdate: for 0 <= i < rows, 0 <= j < cols of a column-major matrix C (and only
// j <= i + row0 when lower_only: the lower triangle of a matrix whose rows [row0, row0 + rows)
// are the ones passed, so a caller can split the rows of a triangle among threads),
//     C(i, j) <- C(i, j) - sum_{k=0}^{r-1} A(i, k) B(j, k),
// with A column-major rows x r and B column-major cols x r, i.e. C -= A B^T. Every element is
// accumulated from acc = 0 in the order k = 0, 1, .., r-1, one fused multiply-add per term
// (acc <- fma(-A(i, k), B(j, k), acc), rounded once), then C(i, j) <- C(i, j) + acc (C is read
// only at the end, so its cache misses overlap the sums). The scalar reference does exactly that
// with std::fma; the SIMD backends do the
// same sequence lane by lane (FNMADD / FMLS round once and negation is exact), so every backend
// gives the same bits. With lower_only, the strictly upper triangle of C is never read or written.
//
// Storage: C(i, j) at C[i + j * ldc], A(i, k) at A[i + k * lda], B(j, k) at B[j + k * ldb];
// ldc, lda >= rows, ldb >= cols. `workspace` holds at least rankUpdateWorkspace(rows, cols, r)
// doubles (the backends copy A and B into tile-ordered panels there); it must not alias the
// operands, and C must not alias A or B. Cost: rows cols r fused multiply-adds, about half that
// with lower_only.
#include <cstddef>

#include "simd/stereo_kernels.hpp"  // Backend

namespace svslam::simd {

struct MatrixKernels {
  Backend backend;
  const char* name;
  void (*rankUpdate)(double* C, std::ptrdiff_t ldc, const double* A, std::ptrdiff_t lda,
                     const double* B, std::ptrdiff_t ldb, int rows, int cols, int r,
                     bool lower_only, int row0, double* workspace);
};

// Doubles of workspace that any backend needs for rankUpdate(rows, cols, r).
std::size_t rankUpdateWorkspace(int rows, int cols, int r);

const MatrixKernels& scalarMatrixKernels();
#if defined(SVSLAM_HAVE_AVX2)
const MatrixKernels& avx2MatrixKernels();  // AVX2 + FMA3
#endif
#if defined(SVSLAM_HAVE_NEON) && defined(__aarch64__)
const MatrixKernels& neonMatrixKernels();  // AArch64 Advanced SIMD (float64x2, FMLS)
#endif

// Whether this CPU can run backend b's matrix kernels (kAuto and kScalar: always).
bool matrixBackendAvailable(Backend b);
// The fastest available backend's table (kAuto), or backend b's; scalar when b is unavailable.
// There is no AVX-512 table: on Zen 4, the target CPU, 512-bit FMAs issue as two 256-bit halves,
// so AVX2 + FMA3 reaches the same peak.
const MatrixKernels& matrixKernels(Backend b = Backend::kAuto);
// True when the selected kernels have a hardware fused multiply-add: a SIMD backend, or the
// scalar one compiled for a target with FMA instructions (FP_FAST_FMA). Otherwise std::fma is
// emulated in software (orders of magnitude slower) and callers should use a non-fused product.
bool matrixKernelsHaveHardwareFma();

}  // namespace svslam::simd

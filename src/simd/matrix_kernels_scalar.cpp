// Scalar reference of the matrix kernels, and the run-time choice among the backends.
#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "simd/matrix_kernels.hpp"

namespace svslam::simd {
namespace {

// The definition of rankUpdate (simd/matrix_kernels.hpp), element by element.
void rankUpdateScalar(double* C, std::ptrdiff_t ldc, const double* A, std::ptrdiff_t lda,
                      const double* B, std::ptrdiff_t ldb, int rows, int cols, int r,
                      bool lower_only, int row0, double*) {
  for (int j = 0; j < cols; ++j)
    for (int i = lower_only ? std::max(0, j - row0) : 0; i < rows; ++i) {
      double acc = 0.0;
      for (int k = 0; k < r; ++k) acc = std::fma(-A[i + k * lda], B[j + k * ldb], acc);
      C[i + j * ldc] += acc;
    }
}

}  // namespace

std::size_t rankUpdateWorkspace(int rows, int cols, int r) {
  if (rows <= 0 || cols <= 0 || r <= 0) return 0;
  // Panels of at most 16 rows (A) and 16 columns (B), zero-padded: (rows + 15) r + (cols + 15) r.
  return (static_cast<std::size_t>(rows) + static_cast<std::size_t>(cols) + 32) *
         static_cast<std::size_t>(r);
}

const MatrixKernels& scalarMatrixKernels() {
  static const MatrixKernels k{Backend::kScalar, "scalar", rankUpdateScalar};
  return k;
}

bool matrixBackendAvailable(Backend b) {
  switch (b) {
    case Backend::kAuto:
    case Backend::kScalar:
      return true;
#if defined(SVSLAM_HAVE_AVX2)
    case Backend::kAvx2:
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#endif
#if defined(SVSLAM_HAVE_NEON) && defined(__aarch64__)
    case Backend::kNeon:
      return true;  // Advanced SIMD with float64 lanes is mandatory on AArch64
#endif
    default:
      return false;
  }
}

const MatrixKernels& matrixKernels(Backend b) {
  if (b == Backend::kAuto) {
    for (Backend c : {Backend::kAvx2, Backend::kNeon})
      if (matrixBackendAvailable(c)) return matrixKernels(c);
    return scalarMatrixKernels();
  }
  if (!matrixBackendAvailable(b)) return scalarMatrixKernels();
  switch (b) {
#if defined(SVSLAM_HAVE_AVX2)
    case Backend::kAvx2:
      return avx2MatrixKernels();
#endif
#if defined(SVSLAM_HAVE_NEON) && defined(__aarch64__)
    case Backend::kNeon:
      return neonMatrixKernels();
#endif
    default:
      return scalarMatrixKernels();
  }
}

bool matrixKernelsHaveHardwareFma() {
#if defined(FP_FAST_FMA)
  return true;
#else
  return matrixKernels().backend != Backend::kScalar;
#endif
}

}  // namespace svslam::simd

#pragma once
// Tiled driver of rankUpdate shared by the SIMD backends (included by each backend's own
// translation unit, which is compiled with its instruction-set flags). Everything here has
// internal linkage, so no instance compiled with, say, AVX2 can stand in for another backend's.
//
// A is copied into panels of MR rows ([panel][k][MR], zero-padded past `rows`) and B into panels
// of NR columns ([panel][k][NR], zero-padded past `cols`); Micro::tile(Ap, Bp, r, C, ldc) updates
// one MR x NR block of C (column-major, leading dimension ldc) with the full sum over k, in
// order. Blocks wholly inside the matrix (and, with lower_only, wholly in the lower triangle) are
// updated in place; blocks on the diagonal or the edge go through a small buffer and only their
// elements inside (and with j <= i + row0) are written back. Columns are taken in chunks of kChunkCols
// so the B panels of a chunk stay in L2 while the A panels stream.
#include <algorithm>
#include <cstddef>

namespace svslam::simd {
namespace {

template <int W>
void packPanels(const double* __restrict__ X, std::ptrdiff_t ldx, int n, int r,
                double* __restrict__ out) {
  // Groups of kGroup panels, column by column within a group: reads of X run along its columns
  // and the writes stay within kGroup output streams.
  constexpr int kGroup = 8;
  const int panels = (n + W - 1) / W;
  for (int p0 = 0; p0 < panels; p0 += kGroup) {
    const int p1 = std::min(panels, p0 + kGroup);
    for (int k = 0; k < r; ++k) {
      const double* __restrict__ x = X + k * ldx;
      for (int p = p0; p < p1; ++p) {
        double* __restrict__ o = out + (static_cast<std::ptrdiff_t>(p) * r + k) * W;
        if (p * W + W <= n) {
          for (int t = 0; t < W; ++t) o[t] = x[p * W + t];
        } else {
          for (int t = 0; t < W; ++t) o[t] = p * W + t < n ? x[p * W + t] : 0.0;
        }
      }
    }
  }
}

template <class Micro>
void rankUpdateTiled(double* C, std::ptrdiff_t ldc, const double* A, std::ptrdiff_t lda,
                     const double* B, std::ptrdiff_t ldb, int rows, int cols, int r,
                     bool lower_only, int row0, double* ws) {
  constexpr int MR = Micro::MR, NR = Micro::NR;
  constexpr int kChunkCols = 32 * NR;
  if (rows <= 0 || cols <= 0 || r <= 0) return;
  const int n_ip = (rows + MR - 1) / MR;
  double* Ap = ws;
  double* Bp = ws + static_cast<std::ptrdiff_t>(n_ip) * r * MR;
  packPanels<MR>(A, lda, rows, r, Ap);
  packPanels<NR>(B, ldb, cols, r, Bp);
  double buf[MR * NR];
  for (int jc = 0; jc < cols; jc += kChunkCols) {
    const int jp_end = (std::min(cols, jc + kChunkCols) + NR - 1) / NR;
    for (int ip = lower_only ? std::max(0, jc - row0) / MR : 0; ip < n_ip; ++ip) {
      const int i0 = ip * MR, g0 = i0 + row0;  // g0: row of the whole matrix
      const double* a = Ap + static_cast<std::ptrdiff_t>(ip) * r * MR;
      for (int jp = jc / NR; jp < jp_end; ++jp) {
        const int j0 = jp * NR;
        if (lower_only && j0 > g0 + MR - 1) break;  // this block and the rest are above it
        const double* b = Bp + static_cast<std::ptrdiff_t>(jp) * r * NR;
        if ((!lower_only || g0 >= j0 + NR - 1) && i0 + MR <= rows && j0 + NR <= cols) {
          Micro::tile(a, b, r, C + i0 + j0 * ldc, ldc);
          continue;
        }
        const auto inside = [&](int i, int j) {
          return i < rows && j < cols && (!lower_only || j <= i + row0);
        };
        for (int u = 0; u < NR; ++u)
          for (int t = 0; t < MR; ++t)
            buf[t + u * MR] = inside(i0 + t, j0 + u) ? C[i0 + t + (j0 + u) * ldc] : 0.0;
        Micro::tile(a, b, r, buf, MR);
        for (int u = 0; u < NR; ++u)
          for (int t = 0; t < MR; ++t)
            if (inside(i0 + t, j0 + u)) C[i0 + t + (j0 + u) * ldc] = buf[t + u * MR];
      }
    }
  }
}

}  // namespace
}  // namespace svslam::simd

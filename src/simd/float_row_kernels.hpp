#pragma once
// Float row kernels of the corner detector (separable convolution rows, gradient products, the
// corner response and non-maximum suppression), one table per instruction set: the portable
// reference, AVX2 (x86-64, chosen at run time) and NEON (AArch64).
//
// Each output element is computed by the same IEEE single-precision operations in the same order
// on every backend (a multiply then an add, never fused: the AVX2 variant is compiled without
// FMA, the NEON one with -ffp-contract=off), so the backends give identical bits; tests hold them to it.
#include "simd/stereo_kernels.hpp"  // Backend

namespace svslam::simd {

struct FloatRowKernels {
  Backend backend;
  const char* name;
  // out[x] = sum_{k=0}^{taps-1} c[k] rows[k][x] for x in [0, n), accumulated from 0.0f in the
  // order k = 0, 1, .. (each product rounded, then added). No output array of a kernel overlaps
  // its inputs.
  void (*convolve)(const float* const* rows, const float* c, int taps, float* out, int n);
  // xx[x] = gx[x]^2, yy[x] = gy[x]^2, xy[x] = gx[x] gy[x] for x in [0, n).
  void (*products)(const float* gx, const float* gy, float* xx, float* yy, float* xy, int n);
  // Corner response of the structure tensor [a b; b c] per pixel, in double, rounded to float:
  //   harris: a c - b^2 - k (a + c)^2          (evaluated as ((a c - b b) - (k (a + c)) (a + c)))
  //   else (Shi-Tomasi): (a + c) / 2 - sqrt((a - c)^2 / 4 + b^2), the smaller eigenvalue.
  // Returns max(max_in, out[0..n)) (NaN responses, never expected, do not raise it).
  float (*response)(const float* a, const float* b, const float* c, bool harris, double k,
                    float* out, int n, float max_in);
  // Non-maximum suppression of one row: writes to xs, in increasing order, every x in [x0, x1)
  // where r = mid[x] is the strict maximum of its 3x3 neighbourhood, ties going to the first in
  // raster order:  r > thr,  r > up[x-1], up[x], up[x+1], mid[x-1],  r >= mid[x+1], down[x-1],
  // down[x], down[x+1]  (ordered comparisons: a NaN is never a maximum). Returns the count.
  // Precondition: 1 <= x0, x1 < the rows' length (x0 - 1 .. x1 are read); xs holds x1 - x0.
  int (*localMaxima)(const float* up, const float* mid, const float* down, float thr, int x0,
                     int x1, int* xs);
};

bool floatRowBackendAvailable(Backend b);  // kAuto and kScalar: always; kAvx2 on x86 with AVX2
// The fastest available backend's table (kAuto), or backend b's (scalar when unavailable).
const FloatRowKernels& floatRowKernels(Backend b = Backend::kAuto);

}  // namespace svslam::simd

#pragma once
// Pieces shared by the AVX2 stereo kernel files (compiled with -mavx2 only; not for other code).
#include <immintrin.h>

#include <cstddef>
#include <cstdint>

#include "simd/stereo_kernels.hpp"

namespace svslam::simd::avx2_detail {

inline __m256i loadu(const void* p) { return _mm256_loadu_si256(static_cast<const __m256i*>(p)); }
inline void storeu(void* p, __m256i v) { _mm256_storeu_si256(static_cast<__m256i*>(p), v); }

// StereoKernels::wtaUpdateRows and ::wtaNeighbours (stereo_kernels_avx2_wta.cpp).
void wtaUpdateRows(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0,
                   int width, int d0, const WtaRowState& s);
void wtaNeighbours(const std::uint16_t* agg, std::ptrdiff_t stride, int num_disp, int width,
                   const WtaRowState& s);

}  // namespace svslam::simd::avx2_detail

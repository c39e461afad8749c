#pragma once
// Row kernels of the dense stereo stage, one table per instruction-set backend.
//
// Every backend computes exactly (bit for bit) what the scalar reference computes; tests hold
// them to it on odd sizes and strides. Layout conventions shared by all kernels:
// - census words: pixel x of a row is one uint64; offset k of the census window (row-major
//   over the window, the centre skipped) is bit (63 - k), set when neighbour < centre.
// - cost rows are "planes": cost[i * stride + x] is the cost of disparity d0 + i at pixel x,
//   uint16; i in [0, num_disp).
#include <cstddef>
#include <cstdint>

namespace svslam::simd {

enum class Backend { kAuto, kScalar, kAvx2, kAvx512, kNeon };

struct StereoKernels {
  Backend backend;
  const char* name;

  // Census transform of one row. `win` points at the top-left pixel of the window of x = 0
  // (i.e. pixel (x - win_w/2, y - win_h/2) of an image padded so every window is readable);
  // `stride` in bytes. Writes out[0 .. width). win_w, win_h odd, win_w * win_h - 1 <= 64.
  void (*censusRow)(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w,
                    int win_h, std::uint64_t* out);

  // cost[i][x] = popcount(left[x] ^ right[x - (d0 + i)]) for x in [0, width).
  // Precondition: right is readable at indices [-(d0 + num_disp - 1), width).
  void (*censusCostRow)(const std::uint64_t* left, const std::uint64_t* right, int width, int d0,
                        int num_disp, std::uint16_t* cost, std::ptrdiff_t cost_stride);

  // cost[i][x] = |left[x] - right[x - (d0 + i)]| (same preconditions as censusCostRow).
  void (*sadCostRow)(const std::uint8_t* left, const std::uint8_t* right, int width, int d0,
                     int num_disp, std::uint16_t* cost, std::ptrdiff_t cost_stride);

  // acc[j] = acc[j] + add[j] - sub[j] (mod 2^16) for j in [0, n); sub may be null (add only).
  void (*addSubRow)(std::uint16_t* acc, const std::uint16_t* add, const std::uint16_t* sub,
                    std::size_t n);

  // Horizontal box sum: out[x] = sum_{k=0}^{win_w-1} in[x + k] for x in [0, width) (mod 2^16).
  void (*boxRow)(const std::uint16_t* in, int width, int win_w, std::uint16_t* out);

  // Left-image winner-take-all: for each x, best_cost[x] = min_i cost[i][x] and best_idx[x] the
  // smallest i reaching it, or -1 when every cost is 0xFFFF (the "impossible" marker).
  void (*wtaLeftRow)(const std::uint16_t* cost, std::ptrdiff_t stride, int width, int num_disp,
                     std::uint16_t* best_cost, std::int16_t* best_idx);

  // second[x] = min of cost[i][x] over i with |i - best_idx[x]| > 1 (0xFFFF when none).
  void (*secondBestRow)(const std::uint16_t* cost, std::ptrdiff_t stride, int width, int num_disp,
                        const std::int16_t* best_idx, std::uint16_t* second);

  // Right-image winner-take-all on the same costs: for right pixel xr the candidates are
  // cost[i][xr + d0 + i]; best_idx_r[xr] = smallest argmin, -1 when all are 0xFFFF.
  // Precondition: row i is readable at [d0 + i, width + d0 + i) (pad with 0xFFFF).
  void (*wtaRightRow)(const std::uint16_t* cost, std::ptrdiff_t stride, int width, int d0,
                      int num_disp, std::int16_t* best_idx_r);
};

const StereoKernels& scalarKernels();
// Backends compiled into this build (CMake defines SVSLAM_HAVE_<BACKEND> for the library).
#if defined(SVSLAM_HAVE_AVX2)
const StereoKernels& avx2Kernels();
#endif
#if defined(SVSLAM_HAVE_AVX512)
const StereoKernels& avx512Kernels();
#endif
#if defined(SVSLAM_HAVE_NEON)
const StereoKernels& neonKernels();
#endif

// True when this build contains the backend and this CPU can run it.
bool backendAvailable(Backend b);
// The fastest available backend (kAuto resolves to this).
Backend bestBackend();
// Kernels of backend b; kAuto picks bestBackend(). Precondition: backendAvailable(b) or kAuto.
const StereoKernels& kernels(Backend b);
const char* backendName(Backend b);
// Parses "auto", "scalar", "avx2", "avx512", "neon"; returns false for anything else.
bool parseBackend(const char* s, Backend& out);

}  // namespace svslam::simd

#pragma once
// Row kernels of the dense stereo stage, one table per instruction-set backend.
//
// Every backend computes exactly (bit for bit) what the scalar reference computes; tests hold
// them to it on odd sizes and strides. Layout conventions shared by all kernels:
// - census words: pixel x of a row is one uint64; offset k of the census window (row-major
//   over the window, the centre skipped) is bit (63 - k), set when neighbour < centre.
// - a cost plane is one uint8 row: cost[x] for one disparity d; aggregated costs are uint16 and
//   0xFFFF marks "no match possible" (x - d < 0).
#include <cstddef>
#include <cstdint>

namespace svslam::simd {

enum class Backend { kAuto, kScalar, kAvx2, kAvx512, kNeon };

// Streaming winner-take-all state of one image row, updated plane by plane (disparity index i
// ascending) by wtaUpdateRow. All arrays have `width` entries. Meaning once every plane is done:
//   best[x]   min_i agg_i[x]; bidx[x] the smallest i reaching it, -1 if every agg is 0xFFFF
//   second[x] min of agg_i[x] over i with |i - bidx[x]| > 1 (0xFFFF if none)
//   cm[x], cp[x]  agg at bidx - 1 and bidx + 1 (0xFFFF when outside the range)
//   best_r[xr], idx_r[xr]  the right image's WTA on the same costs: candidates agg_i[xr + d0 + i],
//                          smallest i on ties, -1 when none is below 0xFFFF
// pm1, pm2 are internal prefix minima (over planes <= i-1 and <= i-2). wtaInitRow sets the start.
struct WtaRowState {
  std::uint16_t* best;
  std::int16_t* bidx;
  std::uint16_t* second;
  std::uint16_t* cm;
  std::uint16_t* cp;
  std::uint16_t* pm1;
  std::uint16_t* pm2;
  std::uint16_t* best_r;
  std::int16_t* idx_r;
};

void wtaInitRow(const WtaRowState& s, int width);

// The left-image part of the scalar reference's wtaUpdateRows on columns [x0, width) only: the
// tail of a vector body (right-image candidates are left to the caller).
void wtaLeftTail(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0, int x0,
                 int width, const WtaRowState& s);

// The right-image update of plane i for right pixels [xr0, n_right): candidate cand[xr] (the
// plane's cost at x = xr + d0 + i) replaces best_r[xr] when strictly smaller.
void wtaRightTail(const std::uint16_t* cand, int xr0, int n_right, int i, const WtaRowState& s);

struct StereoKernels {
  Backend backend;
  const char* name;

  // Census transform of one row. `win` points at the top-left pixel of the window of x = 0
  // (i.e. pixel (x - win_w/2, y - win_h/2) of an image padded so every window is readable);
  // `stride` in bytes. Writes out[0 .. width). win_w, win_h odd, win_w * win_h - 1 <= 64.
  void (*censusRow)(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w, int win_h,
                    std::uint64_t* out);

  // One cost plane: cost[x] = popcount(left[x] ^ right[x - d]) for x in [0, width).
  // Precondition: right is readable at indices [-d, width - d).
  void (*censusCostRow)(const std::uint64_t* left, const std::uint64_t* right, int width, int d,
                        std::uint8_t* cost);

  // One cost plane: cost[x] = |left[x] - right[x - d]| (same preconditions).
  void (*sadCostRow)(const std::uint8_t* left, const std::uint8_t* right, int width, int d,
                     std::uint8_t* cost);

  // acc[j] = acc[j] + add[j] - sub[j] (mod 2^16) for j in [0, n); sub may be null (add only).
  void (*addSubRow)(std::uint16_t* acc, const std::uint8_t* add, const std::uint8_t* sub,
                    std::size_t n);

  // Horizontal box sum: out[x] = sum_{k=0}^{win_w-1} in[x + k] for x in [0, width) (mod 2^16).
  // Precondition: in is readable at [0, width + win_w - 1).
  void (*boxRow)(const std::uint16_t* in, int width, int win_w, std::uint16_t* out);

  // Adds planes i0 .. i0 + n_planes - 1 to the streaming WTA state. Plane i0 + p is the row
  // agg + p * stride (aggregated costs, [0, width)); the row agg - stride must hold plane
  // i0 - 1 (0xFFFF-filled when i0 = 0). Right-image candidates of plane i start at x = d0 + i.
  void (*wtaUpdateRows)(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0,
                        int width, int d0, const WtaRowState& s);
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

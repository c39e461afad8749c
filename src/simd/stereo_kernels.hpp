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
//   cm[x], cp[x]  agg at bidx - 1 and bidx + 1 (0xFFFF when outside the range); the scalar
//                 reference streams them, other backends may leave them stale: wtaNeighbours
//                 sets them from the stored planes once every plane is done
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

// The scalar reference of wtaNeighbours on columns [x0, width).
void wtaNeighboursRange(const std::uint16_t* agg, std::ptrdiff_t stride, int num_disp, int x0,
                        int width, const WtaRowState& s);

// The right-image update of plane i for right pixels [xr0, n_right): candidate cand[xr] (the
// plane's cost at x = xr + d0 + i) replaces best_r[xr] when strictly smaller.
void wtaRightTail(const std::uint16_t* cand, int xr0, int n_right, int i, const WtaRowState& s);

// Per-pixel verdict and sub-pixel refinement of one row (step 4-5 of dense_stereo.hpp), from
// the final WTA state. For pixel x with i = bidx[x], d = d0 + i:
//   failing tests, first one wins: no candidate (i < 0); low texture (low_texture[x] != 0, when
//   low_texture is not null); not unique (uniqueness_pct > 0 and (second == 0xFFFF or
//   100 second <= (100 + uniqueness_pct) best)); reverse correlation (lr_check and, with
//   xr = clamp(x - d, 0, width - 1) and ir = idx_r[xr], ir < 0 or |ir - i| > lr_max_diff);
//   parabola when 0 < i < num_disp - 1, cp != 0xFFFF and v = cm + cp - 2 best > 0;
//   valid pixel: disp = d + (parabola and subpixel ? (cm - cp) / (2 v) : 0) (float division),
//                sigma = sigma_by_denom[parabola ? min(v, max_denom) : 0],
//                curv = parabola ? v * inv_area : 0;
//   invalid pixel: disp = sigma = curv = +inf.
// counts are incremented (never reset). Precondition: idx_r readable at [0, width + 1).
struct FinalizeParams {
  int num_disp;
  int d0;
  int uniqueness_pct;  // 0 disables the test
  bool lr_check;
  int lr_max_diff;
  bool subpixel;
  float inv_area;               // 1 / (window_w * window_h)
  const float* sigma_by_denom;  // max_denom + 1 entries
  int max_denom;
};
struct FinalizeCounts {
  int no_candidate = 0;
  int low_texture = 0;
  int not_unique = 0;
  int lr_inconsistent = 0;
  int valid = 0;
};

// The scalar reference of finalizeRow on columns [x0, width) (vector bodies use it for tails).
void finalizeRange(const WtaRowState& s, const std::uint8_t* low_texture, int x0, int width,
                   const FinalizeParams& p, float* disp, float* sigma, float* curv,
                   FinalizeCounts& counts);

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

  // cm[x] = bidx >= 1 ? agg_{bidx-1}[x] : 0xFFFF and cp[x] = 0 <= bidx < num_disp - 1 ?
  // agg_{bidx+1}[x] : 0xFFFF, plane i being the row agg + i * stride, for x in [0, width).
  // Precondition: rows 0 .. num_disp - 1 readable at [0, width + 1) (32-bit gathers).
  void (*wtaNeighbours)(const std::uint16_t* agg, std::ptrdiff_t stride, int num_disp, int width,
                        const WtaRowState& s);

  // Step 4-5 for one row, as FinalizeParams documents (finalizeRange on [0, width)).
  void (*finalizeRow)(const WtaRowState& s, const std::uint8_t* low_texture, int width,
                      const FinalizeParams& p, float* disp, float* sigma, float* curv,
                      FinalizeCounts& counts);

  // Optional pair (null in backends without it; the stage then uses censusRow and
  // censusCostRow): census words in byte-plane layout. Plane j (0..7) holds byte 7 - j of every
  // pixel's word, i.e. census offsets 8j .. 8j + 7 with offset 8j in bit 7:
  // out[j * plane_stride + x], x in [0, width). Same window preconditions as censusRow.
  void (*censusPlanesRow)(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w,
                          int win_h, std::uint8_t* out, std::ptrdiff_t plane_stride);
  // Cost planes of n_d disparities d = d_first + k, k in [0, n_d), written to
  // cost[k * cost_stride + x] for x in [0, width):
  //   sum_{j < n_planes} popcount(left[j ps + x] ^ right[j ps + x - d]), ps = plane_stride,
  // n_planes in 1..8 (planes j >= ceil((win_w win_h - 1) / 8) are all zero, so the Hamming
  // distance of the words needs only the first ones). Precondition: each right plane readable
  // at [-(d_first + n_d - 1), width - d_first).
  void (*censusPlanesCostRows)(const std::uint8_t* left, const std::uint8_t* right,
                               std::ptrdiff_t plane_stride, int n_planes, int width, int d_first,
                               int n_d, std::uint8_t* cost, std::ptrdiff_t cost_stride);
};

const StereoKernels& scalarKernels();
// Backends compiled into this build (CMake defines SVSLAM_HAVE_<BACKEND> for the library).
#if defined(SVSLAM_HAVE_AVX2)
const StereoKernels& avx2Kernels();
#endif
#if defined(SVSLAM_HAVE_AVX2)
// The AVX2 finalizeRow (stereo_kernels_avx2_finalize.cpp).
void finalizeRowAvx2(const WtaRowState& s, const std::uint8_t* low_texture, int width,
                     const FinalizeParams& p, float* disp, float* sigma, float* curv,
                     FinalizeCounts& counts);
// The AVX2 StereoKernels::wtaNeighbours (gathers), shared with the AVX-512 table.
void wtaNeighboursAvx2(const std::uint16_t* agg, std::ptrdiff_t stride, int num_disp, int width,
                       const WtaRowState& s);
#endif
#if defined(SVSLAM_HAVE_AVX512)
const StereoKernels& avx512Kernels();
// The AVX-512 finalizeRow (stereo_kernels_avx512_finalize.cpp).
void finalizeRowAvx512(const WtaRowState& s, const std::uint8_t* low_texture, int width,
                       const FinalizeParams& p, float* disp, float* sigma, float* curv,
                       FinalizeCounts& counts);
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

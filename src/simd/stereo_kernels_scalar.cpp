// Scalar reference of the stereo row kernels. Plain loops, no intrinsics: this is the
// definition every SIMD backend must reproduce bit for bit.
#include <cstdlib>

#include "simd/stereo_kernels.hpp"

namespace svslam::simd {
namespace {

void censusRow(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w, int win_h,
               std::uint64_t* out) {
  const int cx = win_w / 2;
  const int cy = win_h / 2;
  for (int x = 0; x < width; ++x) {
    const std::uint8_t c = win[cy * stride + cx + x];
    std::uint64_t word = 0;
    int k = 0;
    for (int dy = 0; dy < win_h; ++dy) {
      const std::uint8_t* r = win + dy * stride + x;
      for (int dx = 0; dx < win_w; ++dx) {
        if (dy == cy && dx == cx) continue;
        if (r[dx] < c) word |= std::uint64_t{1} << (63 - k);
        ++k;
      }
    }
    out[x] = word;
  }
}

void censusCostRow(const std::uint64_t* left, const std::uint64_t* right, int width, int d0,
                   int num_disp, std::uint16_t* cost, std::ptrdiff_t cost_stride) {
  for (int i = 0; i < num_disp; ++i) {
    const std::uint64_t* r = right - (d0 + i);
    std::uint16_t* c = cost + i * cost_stride;
    for (int x = 0; x < width; ++x)
      c[x] = static_cast<std::uint16_t>(__builtin_popcountll(left[x] ^ r[x]));
  }
}

void sadCostRow(const std::uint8_t* left, const std::uint8_t* right, int width, int d0,
                int num_disp, std::uint16_t* cost, std::ptrdiff_t cost_stride) {
  for (int i = 0; i < num_disp; ++i) {
    const std::uint8_t* r = right - (d0 + i);
    std::uint16_t* c = cost + i * cost_stride;
    for (int x = 0; x < width; ++x) c[x] = static_cast<std::uint16_t>(std::abs(left[x] - r[x]));
  }
}

void addSubRow(std::uint16_t* acc, const std::uint16_t* add, const std::uint16_t* sub,
               std::size_t n) {
  if (sub == nullptr) {
    for (std::size_t j = 0; j < n; ++j) acc[j] = static_cast<std::uint16_t>(acc[j] + add[j]);
  } else {
    for (std::size_t j = 0; j < n; ++j)
      acc[j] = static_cast<std::uint16_t>(acc[j] + add[j] - sub[j]);
  }
}

void boxRow(const std::uint16_t* in, int width, int win_w, std::uint16_t* out) {
  for (int x = 0; x < width; ++x) {
    std::uint16_t s = 0;
    for (int k = 0; k < win_w; ++k) s = static_cast<std::uint16_t>(s + in[x + k]);
    out[x] = s;
  }
}

void wtaLeftRow(const std::uint16_t* cost, std::ptrdiff_t stride, int width, int num_disp,
                std::uint16_t* best_cost, std::int16_t* best_idx) {
  for (int x = 0; x < width; ++x) {
    best_cost[x] = 0xFFFF;
    best_idx[x] = -1;
  }
  for (int i = 0; i < num_disp; ++i) {
    const std::uint16_t* c = cost + i * stride;
    for (int x = 0; x < width; ++x) {
      if (c[x] < best_cost[x]) {
        best_cost[x] = c[x];
        best_idx[x] = static_cast<std::int16_t>(i);
      }
    }
  }
}

void secondBestRow(const std::uint16_t* cost, std::ptrdiff_t stride, int width, int num_disp,
                   const std::int16_t* best_idx, std::uint16_t* second) {
  for (int x = 0; x < width; ++x) second[x] = 0xFFFF;
  for (int i = 0; i < num_disp; ++i) {
    const std::uint16_t* c = cost + i * stride;
    for (int x = 0; x < width; ++x) {
      if (std::abs(i - best_idx[x]) > 1 && c[x] < second[x]) second[x] = c[x];
    }
  }
}

void wtaRightRow(const std::uint16_t* cost, std::ptrdiff_t stride, int width, int d0,
                 int num_disp, std::int16_t* best_idx_r) {
  for (int xr = 0; xr < width; ++xr) {
    std::uint16_t best = 0xFFFF;
    std::int16_t idx = -1;
    for (int i = 0; i < num_disp; ++i) {
      const std::uint16_t c = cost[i * stride + xr + d0 + i];
      if (c < best) {
        best = c;
        idx = static_cast<std::int16_t>(i);
      }
    }
    best_idx_r[xr] = idx;
  }
}

}  // namespace

const StereoKernels& scalarKernels() {
  static const StereoKernels k{Backend::kScalar, "scalar", censusRow,  censusCostRow,
                               sadCostRow,        addSubRow, boxRow,    wtaLeftRow,
                               secondBestRow,     wtaRightRow};
  return k;
}

}  // namespace svslam::simd

// Scalar reference of the stereo row kernels. Plain loops, no intrinsics: this is the
// definition every SIMD backend must reproduce bit for bit.
#include <algorithm>
#include <cstdlib>
#include <limits>

#include "simd/stereo_kernels.hpp"

namespace svslam::simd {

void wtaInitRow(const WtaRowState& s, int width) {
  for (int x = 0; x < width; ++x) {
    s.best[x] = s.second[x] = s.cm[x] = s.cp[x] = s.pm1[x] = s.pm2[x] = s.best_r[x] = 0xFFFF;
    s.bidx[x] = s.idx_r[x] = -1;
  }
}

void wtaLeftTail(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0, int x0,
                 int width, const WtaRowState& s) {
  if (x0 >= width) return;
  // The reference on the sub-range, with d0 = its width so that no right-image pixel is touched.
  const WtaRowState t{s.best + x0, s.bidx + x0, s.second + x0, s.cm + x0, s.cp + x0,
                      s.pm1 + x0,  s.pm2 + x0,  s.best_r,      s.idx_r};
  scalarKernels().wtaUpdateRows(agg + x0, stride, n_planes, i0, width - x0, width - x0, t);
}

void wtaRightTail(const std::uint16_t* cand, int xr0, int n_right, int i, const WtaRowState& s) {
  for (int xr = xr0; xr < n_right; ++xr) {
    if (cand[xr] < s.best_r[xr]) {
      s.best_r[xr] = cand[xr];
      s.idx_r[xr] = static_cast<std::int16_t>(i);
    }
  }
}

void wtaNeighboursRange(const std::uint16_t* agg, std::ptrdiff_t stride, int num_disp, int x0,
                        int width, const WtaRowState& s) {
  for (int x = x0; x < width; ++x) {
    const int b = s.bidx[x];
    s.cm[x] = b >= 1 ? agg[(b - 1) * stride + x] : std::uint16_t{0xFFFF};
    s.cp[x] = b >= 0 && b + 1 < num_disp ? agg[(b + 1) * stride + x] : std::uint16_t{0xFFFF};
  }
}

void finalizeRange(const WtaRowState& s, const std::uint8_t* low_texture, int x0, int width,
                   const FinalizeParams& p, float* disp, float* sigma, float* curv,
                   FinalizeCounts& counts) {
  const float inf = std::numeric_limits<float>::infinity();
  const std::uint64_t uniq_factor = 100u + static_cast<std::uint32_t>(p.uniqueness_pct);
  for (int x = x0; x < width; ++x) {
    const int idx = s.bidx[x];
    const std::uint32_t best = s.best[x];
    const std::uint32_t second = s.second[x];
    const bool no_candidate = idx < 0;
    const bool low_tex = low_texture != nullptr && low_texture[x] != 0;
    // No competitor at all (fewer than 3 candidates, at the left border) cannot be verified.
    const bool not_unique =
        p.uniqueness_pct > 0 &&
        (second == 0xFFFF || static_cast<std::uint64_t>(second) * 100u <= best * uniq_factor);
    const int xr = std::clamp(x - (p.d0 + idx), 0, width - 1);
    const int idr = s.idx_r[xr];
    const bool lr_bad = p.lr_check && (idr < 0 || std::abs(idr - idx) > p.lr_max_diff);
    // The first failing test is the pixel's verdict.
    if (no_candidate) {
      ++counts.no_candidate;
    } else if (low_tex) {
      ++counts.low_texture;
    } else if (not_unique) {
      ++counts.not_unique;
    } else if (lr_bad) {
      ++counts.lr_inconsistent;
    } else {
      ++counts.valid;
    }
    const bool valid = !(no_candidate || low_tex || not_unique || lr_bad);
    const int cm = s.cm[x];
    const int cp = s.cp[x];
    const int denom = cm + cp - 2 * static_cast<int>(best);
    const bool parabola = idx > 0 && idx + 1 < p.num_disp && cp != 0xFFFF && denom > 0;
    const float delta = parabola && p.subpixel
                            ? static_cast<float>(cm - cp) / static_cast<float>(2 * denom)
                            : 0.0f;
    disp[x] = valid ? static_cast<float>(p.d0 + idx) + delta : inf;
    sigma[x] = valid ? p.sigma_by_denom[parabola ? std::min(denom, p.max_denom) : 0] : inf;
    curv[x] = valid ? (parabola ? static_cast<float>(denom) * p.inv_area : 0.0f) : inf;
  }
}

namespace {

void wtaNeighbours(const std::uint16_t* agg, std::ptrdiff_t stride, int num_disp, int width,
                   const WtaRowState& s) {
  wtaNeighboursRange(agg, stride, num_disp, 0, width, s);
}

void finalizeRow(const WtaRowState& s, const std::uint8_t* low_texture, int width,
                 const FinalizeParams& p, float* disp, float* sigma, float* curv,
                 FinalizeCounts& counts) {
  finalizeRange(s, low_texture, 0, width, p, disp, sigma, curv, counts);
}

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

void censusPlanesRow(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w,
                     int win_h, std::uint8_t* out, std::ptrdiff_t plane_stride) {
  for (int x = 0; x < width; ++x) {
    std::uint64_t word = 0;
    censusRow(win + x, stride, 1, win_w, win_h, &word);
    for (int j = 0; j < 8; ++j)
      out[j * plane_stride + x] = static_cast<std::uint8_t>(word >> (56 - 8 * j));
  }
}

void censusPlanesCostRows(const std::uint8_t* left, const std::uint8_t* right,
                          std::ptrdiff_t plane_stride, int n_planes, int width, int d_first,
                          int n_d, std::uint8_t* cost, std::ptrdiff_t cost_stride) {
  for (int k = 0; k < n_d; ++k) {
    const int d = d_first + k;
    for (int x = 0; x < width; ++x) {
      int c = 0;
      for (int j = 0; j < n_planes; ++j)
        c += __builtin_popcount(left[j * plane_stride + x] ^ right[j * plane_stride + x - d]);
      cost[k * cost_stride + x] = static_cast<std::uint8_t>(c);
    }
  }
}

void censusCostRow(const std::uint64_t* left, const std::uint64_t* right, int width, int d,
                   std::uint8_t* cost) {
  const std::uint64_t* r = right - d;
  for (int x = 0; x < width; ++x)
    cost[x] = static_cast<std::uint8_t>(__builtin_popcountll(left[x] ^ r[x]));
}

void sadCostRow(const std::uint8_t* left, const std::uint8_t* right, int width, int d,
                std::uint8_t* cost) {
  const std::uint8_t* r = right - d;
  for (int x = 0; x < width; ++x) cost[x] = static_cast<std::uint8_t>(std::abs(left[x] - r[x]));
}

void addSubRow(std::uint16_t* acc, const std::uint8_t* add, const std::uint8_t* sub,
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

void wtaUpdateRows(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0, int width,
                   int d0, const WtaRowState& s) {
  for (int p = 0; p < n_planes; ++p) {
    const int i = i0 + p;
    const std::uint16_t* a = agg + p * stride;
    const std::uint16_t* prev = a - stride;
    for (int x = 0; x < width; ++x) {
      const std::uint16_t c = a[x];
      if (c < s.best[x]) {
        s.second[x] = s.pm2[x];  // every plane <= i - 2 is a non-neighbour of the new best
        s.best[x] = c;
        s.bidx[x] = static_cast<std::int16_t>(i);
        s.cm[x] = prev[x];
        s.cp[x] = 0xFFFF;
      } else if (i == s.bidx[x] + 1) {
        s.cp[x] = c;
      } else if (c < s.second[x]) {
        s.second[x] = c;
      }
      s.pm2[x] = s.pm1[x];
      if (c < s.pm1[x]) s.pm1[x] = c;
    }
    wtaRightTail(a + d0 + i, 0, width - (d0 + i), i, s);
  }
}

}  // namespace

const StereoKernels& scalarKernels() {
  static const StereoKernels k{Backend::kScalar, "scalar",  censusRow, censusCostRow,
                               sadCostRow,       addSubRow, boxRow,    wtaUpdateRows,
                               wtaNeighbours,    finalizeRow,      censusPlanesRow, censusPlanesCostRows};
  return k;
}

}  // namespace svslam::simd

// NEON backend of the stereo row kernels (AArch64, and armv7 built with -mfpu=neon): 16 pixels
// per step for census and SAD, 8 uint16 lanes per step elsewhere, scalar tails. Bit-exact with
// stereo_kernels_scalar.cpp.
#if !defined(__ARM_NEON) && !defined(__ARM_NEON__)
#error "stereo_kernels_neon.cpp needs NEON: AArch64, or 32-bit ARM with -mfpu=neon"
#endif
#if defined(__ARM_BIG_ENDIAN)
#error "stereo_kernels_neon.cpp assumes a little-endian target"
#endif

#include <arm_neon.h>

#include <cstdlib>

#include "simd/stereo_kernels.hpp"

namespace svslam::simd {
namespace {

// Byte plane j holds census offsets 8j..8j+7 of 16 pixels, MSB first; it is byte 7 - j of each
// pixel's word. Transposes the planes into 16 words with zips of 8, 16 and 32 bits.
inline void transposeStore(const uint8x16_t* pl, std::uint64_t* out) {
  const uint8x16x2_t a = vzipq_u8(pl[7], pl[6]);  // val[0]: pixels 0-7, val[1]: 8-15
  const uint8x16x2_t b = vzipq_u8(pl[5], pl[4]);
  const uint8x16x2_t c = vzipq_u8(pl[3], pl[2]);
  const uint8x16x2_t d = vzipq_u8(pl[1], pl[0]);
  for (int h = 0; h < 2; ++h) {  // pixels 8h .. 8h + 7
    const uint16x8x2_t ab =
        vzipq_u16(vreinterpretq_u16_u8(a.val[h]), vreinterpretq_u16_u8(b.val[h]));
    const uint16x8x2_t cd =
        vzipq_u16(vreinterpretq_u16_u8(c.val[h]), vreinterpretq_u16_u8(d.val[h]));
    for (int q = 0; q < 2; ++q) {  // pixels 8h + 4q .. + 3
      const uint32x4x2_t w =
          vzipq_u32(vreinterpretq_u32_u16(ab.val[q]), vreinterpretq_u32_u16(cd.val[q]));
      std::uint64_t* o = out + 8 * h + 4 * q;
      vst1q_u64(o, vreinterpretq_u64_u32(w.val[0]));
      vst1q_u64(o + 2, vreinterpretq_u64_u32(w.val[1]));
    }
  }
}

void censusRow(const std::uint8_t* win, std::ptrdiff_t stride, int width, int win_w, int win_h,
               std::uint64_t* out) {
  const int cx = win_w / 2;
  const int cy = win_h / 2;
  int x = 0;
  for (; x + 16 <= width; x += 16) {
    const uint8x16_t c = vld1q_u8(win + cy * stride + cx + x);
    uint8x16_t planes[8];
    for (uint8x16_t& p : planes) p = vdupq_n_u8(0);
    uint8x16_t acc = vdupq_n_u8(0);
    int k = 0;
    for (int dy = 0; dy < win_h; ++dy) {
      const std::uint8_t* r = win + dy * stride + x;
      for (int dx = 0; dx < win_w; ++dx) {
        if (dy == cy && dx == cx) continue;
        const uint8x16_t lt = vcltq_u8(vld1q_u8(r + dx), c);  // 0xFF where neighbour < centre
        acc = vsubq_u8(vaddq_u8(acc, acc), lt);               // acc = acc << 1 | lt
        if ((++k & 7) == 0) {
          planes[(k >> 3) - 1] = acc;
          acc = vdupq_n_u8(0);
        }
      }
    }
    if ((k & 7) != 0) {  // partial last plane: move its first offset up to bit 7
      planes[k >> 3] = vshlq_u8(acc, vdupq_n_s8(static_cast<std::int8_t>(8 - (k & 7))));
    }
    transposeStore(planes, out + x);
  }
  if (x < width) scalarKernels().censusRow(win + x, stride, width - x, win_w, win_h, out + x);
}

// Population counts of 8 words (p[0..3] hold 2 words each) as 8 uint16.
// Population counts of 16 words (v[k] holds words 2k, 2k + 1) as 16 bytes.
inline uint8x16_t popcount16(const uint64x2_t* v) {
  uint8x16_t c[8];
  for (int k = 0; k < 8; ++k) c[k] = vcntq_u8(vreinterpretq_u8_u64(v[k]));
#if defined(__aarch64__)
  // Pairwise byte sums: 8 -> 4 -> 2 -> 1 bytes per word.
  const uint8x16_t s0 = vpaddq_u8(vpaddq_u8(c[0], c[1]), vpaddq_u8(c[2], c[3]));
  const uint8x16_t s1 = vpaddq_u8(vpaddq_u8(c[4], c[5]), vpaddq_u8(c[6], c[7]));
  return vpaddq_u8(s0, s1);
#else
  uint16x4_t w[4];
  for (int k = 0; k < 4; ++k) {
    const uint64x2_t a = vpaddlq_u32(vpaddlq_u16(vpaddlq_u8(c[2 * k])));
    const uint64x2_t b = vpaddlq_u32(vpaddlq_u16(vpaddlq_u8(c[2 * k + 1])));
    w[k] = vmovn_u32(vcombine_u32(vmovn_u64(a), vmovn_u64(b)));
  }
  return vcombine_u8(vmovn_u16(vcombine_u16(w[0], w[1])), vmovn_u16(vcombine_u16(w[2], w[3])));
#endif
}

void censusCostRow(const std::uint64_t* left, const std::uint64_t* right, int width, int d,
                   std::uint8_t* cost) {
  const std::uint64_t* r = right - d;
  int x = 0;
  for (; x + 16 <= width; x += 16) {
    uint64x2_t v[8];
    for (int k = 0; k < 8; ++k)
      v[k] = veorq_u64(vld1q_u64(left + x + 2 * k), vld1q_u64(r + x + 2 * k));
    vst1q_u8(cost + x, popcount16(v));
  }
  for (; x < width; ++x) cost[x] = static_cast<std::uint8_t>(__builtin_popcountll(left[x] ^ r[x]));
}

void sadCostRow(const std::uint8_t* left, const std::uint8_t* right, int width, int d,
                std::uint8_t* cost) {
  const std::uint8_t* r = right - d;
  int x = 0;
  for (; x + 16 <= width; x += 16)
    vst1q_u8(cost + x, vabdq_u8(vld1q_u8(left + x), vld1q_u8(r + x)));
  if (x + 8 <= width) {
    vst1_u8(cost + x, vabd_u8(vld1_u8(left + x), vld1_u8(r + x)));
    x += 8;
  }
  for (; x < width; ++x) cost[x] = static_cast<std::uint8_t>(std::abs(left[x] - r[x]));
}

void addSubRow(std::uint16_t* acc, const std::uint8_t* add, const std::uint8_t* sub,
               std::size_t n) {
  std::size_t j = 0;
  if (sub == nullptr) {
    for (; j + 8 <= n; j += 8) vst1q_u16(acc + j, vaddw_u8(vld1q_u16(acc + j), vld1_u8(add + j)));
    for (; j < n; ++j) acc[j] = static_cast<std::uint16_t>(acc[j] + add[j]);
  } else {
    for (; j + 8 <= n; j += 8) {
      const uint16x8_t s = vaddw_u8(vld1q_u16(acc + j), vld1_u8(add + j));
      vst1q_u16(acc + j, vsubw_u8(s, vld1_u8(sub + j)));
    }
    for (; j < n; ++j) acc[j] = static_cast<std::uint16_t>(acc[j] + add[j] - sub[j]);
  }
}

void boxRow(const std::uint16_t* in, int width, int win_w, std::uint16_t* out) {
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    uint16x8_t s0 = vdupq_n_u16(0);
    uint16x8_t s1 = vdupq_n_u16(0);
    int k = 0;
    for (; k + 2 <= win_w; k += 2) {
      s0 = vaddq_u16(s0, vld1q_u16(in + x + k));
      s1 = vaddq_u16(s1, vld1q_u16(in + x + k + 1));
    }
    if (k < win_w) s0 = vaddq_u16(s0, vld1q_u16(in + x + k));
    vst1q_u16(out + x, vaddq_u16(s0, s1));
  }
  for (; x < width; ++x) {
    std::uint16_t s = 0;
    for (int k = 0; k < win_w; ++k) s = static_cast<std::uint16_t>(s + in[x + k]);
    out[x] = s;
  }
}

// The left state of 8 columns stays in registers across the planes; the branches of the
// reference become bit selects.
void wtaUpdateRows(const std::uint16_t* agg, std::ptrdiff_t stride, int n_planes, int i0, int width,
                   int d0, const WtaRowState& s) {
  const uint16x8_t ones = vdupq_n_u16(0xFFFF);
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    uint16x8_t best = vld1q_u16(s.best + x);
    uint16x8_t second = vld1q_u16(s.second + x);
    uint16x8_t pm1 = vld1q_u16(s.pm1 + x);
    uint16x8_t pm2 = vld1q_u16(s.pm2 + x);
    int16x8_t bidx = vld1q_s16(s.bidx + x);
    uint16x8_t cm = vld1q_u16(s.cm + x);
    uint16x8_t cp = vld1q_u16(s.cp + x);
    uint16x8_t prev = vld1q_u16(agg - stride + x);
    for (int p = 0; p < n_planes; ++p) {
      const int i = i0 + p;
      const uint16x8_t c = vld1q_u16(agg + p * stride + x);
      const uint16x8_t m_new = vcltq_u16(c, best);
      // i == bidx + 1, as int: no int16 bidx matches when i - 1 > 32767.
      const uint16x8_t eq_adj =
          i - 1 > 32767 ? vdupq_n_u16(0)
                        : vceqq_s16(bidx, vdupq_n_s16(static_cast<std::int16_t>(i - 1)));
      const uint16x8_t m_adj = vbicq_u16(eq_adj, m_new);
      const uint16x8_t m_sec = vbicq_u16(vcltq_u16(c, second), vorrq_u16(m_new, m_adj));
      second = vbslq_u16(m_sec, c, vbslq_u16(m_new, pm2, second));
      best = vminq_u16(best, c);
      bidx = vbslq_s16(m_new, vdupq_n_s16(static_cast<std::int16_t>(i)), bidx);
      cm = vbslq_u16(m_new, prev, cm);
      cp = vbslq_u16(m_adj, c, vbslq_u16(m_new, ones, cp));
      pm2 = pm1;
      pm1 = vminq_u16(pm1, c);
      prev = c;
    }
    vst1q_u16(s.best + x, best);
    vst1q_u16(s.second + x, second);
    vst1q_u16(s.pm1 + x, pm1);
    vst1q_u16(s.pm2 + x, pm2);
    vst1q_s16(s.bidx + x, bidx);
    vst1q_u16(s.cm + x, cm);
    vst1q_u16(s.cp + x, cp);
  }
  if (x < width) wtaLeftTail(agg, stride, n_planes, i0, x, width, s);

  // Right image: plane i's candidate for right pixel xr is agg_i[xr + d0 + i].
  for (int p = 0; p < n_planes; ++p) {
    const int i = i0 + p;
    const int n_right = width - (d0 + i);
    if (n_right <= 0) continue;
    const std::uint16_t* a = agg + p * stride + (d0 + i);
    const int16x8_t vi = vdupq_n_s16(static_cast<std::int16_t>(i));
    int xr = 0;
    for (; xr + 8 <= n_right; xr += 8) {
      const uint16x8_t c = vld1q_u16(a + xr);
      const uint16x8_t br = vld1q_u16(s.best_r + xr);
      const uint16x8_t lt = vcltq_u16(c, br);
      vst1q_u16(s.best_r + xr, vminq_u16(br, c));
      vst1q_s16(s.idx_r + xr, vbslq_s16(lt, vi, vld1q_s16(s.idx_r + xr)));
    }
    wtaRightTail(a, xr, n_right, i, s);
  }
}

}  // namespace

namespace {
// Step 4-5 stays on the scalar reference on ARM (per pixel, not per pixel-disparity).
void finalizeRowNeon(const WtaRowState& s, const std::uint8_t* low_texture, int width,
                     const FinalizeParams& p, float* disp, float* sigma, float* curv,
                     FinalizeCounts& counts) {
  finalizeRange(s, low_texture, 0, width, p, disp, sigma, curv, counts);
}
}  // namespace

namespace {
// cm / cp from the stored planes: per pixel, not per pixel-disparity, so the reference.
void wtaNeighboursScalar(const std::uint16_t* agg, std::ptrdiff_t stride, int num_disp, int width,
                         const WtaRowState& s) {
  wtaNeighboursRange(agg, stride, num_disp, 0, width, s);
}
}  // namespace

const StereoKernels& neonKernels() {
  static const StereoKernels k{Backend::kNeon, "neon",    censusRow, censusCostRow,
                               sadCostRow,     addSubRow, boxRow,    wtaUpdateRows,
                               wtaNeighboursScalar, finalizeRowNeon,  nullptr,   nullptr};
  return k;
}

}  // namespace svslam::simd

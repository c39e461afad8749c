#pragma once
// Patch similarity for point matching: zero-mean normalised cross-correlation (ZNCC) of two
// square patches of side 2 h + 1 centred on integer pixels,
//     zncc = sum (a - mean a)(b - mean b) / sqrt(sum (a - mean a)^2 * sum (b - mean b)^2),
// in [-1, 1]; 1 = identical up to gain and offset. Flat patches (no variance) score -1 so they
// never win a match.
#include <cstdint>
#include <vector>

#include "core/image.hpp"

namespace svslam {

// True when the patch of half size h centred on (x, y) lies inside the image.
inline bool patchInside(ImageView<const std::uint8_t> img, int x, int y, int h) {
  return x - h >= 0 && y - h >= 0 && x + h < img.width && y + h < img.height;
}

// Precondition: both patches inside their images (patchInside).
float zncc(ImageView<const std::uint8_t> a, int xa, int ya, ImageView<const std::uint8_t> b,
           int xb, int yb, int h);

// The statistics of a fixed patch, for scanning it against many candidates.
struct PatchStats {
  int x = 0, y = 0, h = 0;
  std::int64_t sum = 0;
  double inv_norm = 0;  // 1 / sqrt(n sum a^2 - (sum a)^2), 0 for a flat patch
};
PatchStats patchStats(ImageView<const std::uint8_t> a, int x, int y, int h);
// zncc of the fixed patch `pa` of image `a` against the patch of `b` at (xb, yb).
float zncc(ImageView<const std::uint8_t> a, const PatchStats& pa, ImageView<const std::uint8_t> b,
           int xb, int yb);

// Scratch space of znccRow, kept by the caller between calls (no allocation once warm).
struct ZnccRowScratch {
  std::vector<std::int32_t> sab, col_sum, col_sq;
};

// A row scan: out[j] = zncc(a, pa, b, xb_first + j, yb) for j in [0, n), bit for bit the same
// values as the single-candidate zncc (the sums are exact integers; the final float expression
// is the same). The patch sums of `b` come from column sums shared by neighbouring candidates,
// and the cross products are accumulated over the candidates in vectorisable loops.
// Precondition: every candidate patch inside `b`; n >= 1.
void znccRow(ImageView<const std::uint8_t> a, const PatchStats& pa, ImageView<const std::uint8_t> b,
             int xb_first, int yb, int n, float* out, ZnccRowScratch& scratch);

}  // namespace svslam

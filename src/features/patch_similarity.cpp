#include "features/patch_similarity.hpp"

#include <cmath>

namespace svslam {

PatchStats patchStats(ImageView<const std::uint8_t> a, int x, int y, int h) {
  PatchStats s;
  s.x = x;
  s.y = y;
  s.h = h;
  std::int64_t sum = 0, sum2 = 0;
  for (int dy = -h; dy <= h; ++dy) {
    const std::uint8_t* r = a.row(y + dy) + x - h;
    for (int i = 0; i <= 2 * h; ++i) {
      sum += r[i];
      sum2 += r[i] * r[i];
    }
  }
  const std::int64_t n = (2 * h + 1) * (2 * h + 1);
  const std::int64_t var = n * sum2 - sum * sum;
  s.sum = sum;
  s.inv_norm = var > 0 ? 1.0 / std::sqrt(static_cast<double>(var)) : 0.0;
  return s;
}

float zncc(ImageView<const std::uint8_t> a, const PatchStats& pa, ImageView<const std::uint8_t> b,
           int xb, int yb) {
  const int h = pa.h;
  std::int32_t sb = 0, sbb = 0, sab = 0;  // (2h+1)^2 * 255^2 < 2^31 for h <= 45
  for (int dy = -h; dy <= h; ++dy) {
    const std::uint8_t* ra = a.row(pa.y + dy) + pa.x - h;
    const std::uint8_t* rb = b.row(yb + dy) + xb - h;
    for (int i = 0; i <= 2 * h; ++i) {
      const std::int32_t vb = rb[i];
      sb += vb;
      sbb += vb * vb;
      sab += ra[i] * vb;
    }
  }
  const std::int64_t n = (2 * h + 1) * (2 * h + 1);
  const std::int64_t var_b = n * static_cast<std::int64_t>(sbb) - static_cast<std::int64_t>(sb) * sb;
  if (pa.inv_norm == 0.0 || var_b <= 0) return -1.0f;
  const double cov = static_cast<double>(n * static_cast<std::int64_t>(sab) - pa.sum * sb);
  return static_cast<float>(cov * pa.inv_norm / std::sqrt(static_cast<double>(var_b)));
}

void znccRow(ImageView<const std::uint8_t> a, const PatchStats& pa, ImageView<const std::uint8_t> b,
             int xb_first, int yb, int n, float* out, ZnccRowScratch& scratch) {
  const int h = pa.h, side = 2 * h + 1;
  const std::size_t un = static_cast<std::size_t>(n);
  const std::size_t ncol = un + static_cast<std::size_t>(2 * h);
  scratch.sab.assign(un, 0);
  scratch.col_sum.assign(ncol, 0);
  scratch.col_sq.assign(ncol, 0);
  std::int32_t* sab = scratch.sab.data();
  std::int32_t* cs = scratch.col_sum.data();
  std::int32_t* cq = scratch.col_sq.data();
  for (int dy = -h; dy <= h; ++dy) {
    const std::uint8_t* ra = a.row(pa.y + dy) + pa.x - h;
    const std::uint8_t* rb = b.row(yb + dy) + xb_first - h;  // column c = pixel xb_first - h + c
    for (std::size_t c = 0; c < ncol; ++c) {
      const std::int32_t v = rb[c];
      cs[c] += v;
      cq[c] += v * v;
    }
    for (int i = 0; i < side; ++i) {
      const std::uint16_t av = ra[i];
      const std::uint8_t* p = rb + i;
      for (std::size_t j = 0; j < un; ++j)
        sab[j] += static_cast<std::uint16_t>(av * static_cast<std::uint16_t>(p[j]));
    }
  }
  const std::int64_t np = static_cast<std::int64_t>(side) * side;
  for (std::size_t j = 0; j < un; ++j) {
    std::int32_t sb = 0, sbb = 0;
    for (int i = 0; i < side; ++i) {
      sb += cs[j + static_cast<std::size_t>(i)];
      sbb += cq[j + static_cast<std::size_t>(i)];
    }
    const std::int64_t var_b = np * static_cast<std::int64_t>(sbb) - static_cast<std::int64_t>(sb) * sb;
    if (pa.inv_norm == 0.0 || var_b <= 0) {
      out[j] = -1.0f;
      continue;
    }
    const double cov = static_cast<double>(np * static_cast<std::int64_t>(sab[j]) - pa.sum * sb);
    out[j] = static_cast<float>(cov * pa.inv_norm / std::sqrt(static_cast<double>(var_b)));
  }
}

float zncc(ImageView<const std::uint8_t> a, int xa, int ya, ImageView<const std::uint8_t> b,
           int xb, int yb, int h) {
  return zncc(a, patchStats(a, xa, ya, h), b, xb, yb);
}

}  // namespace svslam

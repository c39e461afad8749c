#include "slam/patch_tracking.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "features/patch_similarity.hpp"
#include "features/subpixel_refine.hpp"

namespace svslam {

void samplePatch(ImageView<const std::uint8_t> img, double u, double v, int h, std::uint8_t* out) {
  const int x0 = static_cast<int>(std::floor(u)), y0 = static_cast<int>(std::floor(v));
  const double ax = u - x0, ay = v - y0;
  const double w00 = (1 - ax) * (1 - ay), w10 = ax * (1 - ay), w01 = (1 - ax) * ay, w11 = ax * ay;
  for (int dy = -h; dy <= h; ++dy) {
    const std::uint8_t* r0 = img.row(y0 + dy);
    const std::uint8_t* r1 = img.row(y0 + dy + 1);
    for (int dx = -h; dx <= h; ++dx) {
      const int x = x0 + dx;
      const double g = w00 * r0[x] + w10 * r0[x + 1] + w01 * r1[x] + w11 * r1[x + 1];
      *out++ = static_cast<std::uint8_t>(std::lround(std::clamp(g, 0.0, 255.0)));
    }
  }
}

bool insideWithMargin(ImageView<const std::uint8_t> img, double u, double v, int m) {
  return u >= m && v >= m && u < img.width - m - 1 && v < img.height - m - 1;
}

bool findPatch(ImageView<const std::uint8_t> img, const std::uint8_t* tmpl, int h, int pu, int pv,
               int r, float min_zncc, double& u, double& v) {
  const int side = 2 * h + 1;
  const int x0 = std::max(h + 2, pu - r), x1 = std::min(img.width - h - 3, pu + r);
  const int y0 = std::max(h + 2, pv - r), y1 = std::min(img.height - h - 3, pv + r);
  if (x1 < x0 || y1 < y0) return false;
  const ImageView<const std::uint8_t> patch(tmpl, side, side, side);
  const PatchStats ps = patchStats(patch, h, h, h);
  if (ps.inv_norm == 0.0) return false;
  int bx = -1, by = -1;
  float best = min_zncc;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const float sc = zncc(patch, ps, img, x, y);
      if (sc > best) {
        best = sc;
        bx = x;
        by = y;
      }
    }
  if (bx < 0) return false;
  u = bx;
  v = by;
  double u_ref = 0, v_ref = 0;
  if (refineTranslation(tmpl, h, img, u, v, SubpixelRefineParams{}, u_ref, v_ref) &&
      std::abs(u_ref - bx) <= 1.0 && std::abs(v_ref - by) <= 1.0) {
    u = u_ref;
    v = v_ref;
  }
  return insideWithMargin(img, u, v, h + 2);
}

}  // namespace svslam

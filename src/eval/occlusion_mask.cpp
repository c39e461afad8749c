#include "eval/occlusion_mask.hpp"

#include <cmath>
#include <vector>

namespace svslam {

ImageU8 nonOccludedMask(ImageView<const float> gt_px, float tolerance_px) {
  ImageU8 mask(gt_px.width, gt_px.height);
  std::vector<float> zbuf(static_cast<std::size_t>(gt_px.width));
  for (int y = 0; y < gt_px.height; ++y) {
    const float* g = gt_px.row(y);
    std::fill(zbuf.begin(), zbuf.end(), 0.0f);
    for (int x = 0; x < gt_px.width; ++x) {
      if (!std::isfinite(g[x]) || !(g[x] > 0.0f)) continue;
      const long xr = std::lround(x - g[x]);
      if (xr >= 0 && xr < gt_px.width)
        zbuf[static_cast<std::size_t>(xr)] = std::max(zbuf[static_cast<std::size_t>(xr)], g[x]);
    }
    std::uint8_t* m = mask.row(y);
    for (int x = 0; x < gt_px.width; ++x) {
      m[x] = 0;
      if (!std::isfinite(g[x]) || !(g[x] > 0.0f)) continue;
      const long xr = std::lround(x - g[x]);
      if (xr < 0 || xr >= gt_px.width) continue;
      if (zbuf[static_cast<std::size_t>(xr)] > g[x] + tolerance_px) continue;
      m[x] = 255;
    }
  }
  return mask;
}

}  // namespace svslam

#include "pipeline/tools/point_sigma_samples.hpp"

#include <cmath>

namespace svslam::cli {

Status collectPointSamples(const LoadedCase& c, const CornerParams& corners,
                           StereoMatchParams match, std::vector<float>& kappa,
                           std::vector<float>& abs_err, int* matches) {
  if (c.left.empty() || c.right.empty())
    return Status::invalidArgument(c.info.name + ": images not loaded");
  match.max_disp_px = std::max(c.info.max_disp + 1, match.min_disp_px + 3);
  CornerDetector detector(corners, c.left.width(), c.left.height());
  if (!detector.initStatus()) return detector.initStatus();
  StereoPointMatcher matcher(match);
  if (!matcher.initStatus()) return matcher.initStatus();
  std::vector<Corner> found;
  if (Status s = detector.process(c.left.cview(), found); !s) return s;
  std::vector<Eigen::Vector2f> pts;
  pts.reserve(found.size());
  for (const Corner& k : found) pts.emplace_back(k.x_px, k.y_px);
  std::vector<StereoMatch> out;
  StereoMatchStats stats;
  if (Status s = matcher.process(c.left.cview(), c.right.cview(), pts, {}, out, stats); !s)
    return Status(s.code(), c.info.name + ": " + s.message());
  if (matches) *matches = static_cast<int>(out.size());
  for (const StereoMatch& m : out) {
    const int x = static_cast<int>(std::lround(m.u_px));
    const int y = static_cast<int>(std::lround(m.v_px));
    const float g = c.gt(x, y);
    if (!std::isfinite(g) || !(g > 0.0f)) continue;
    if (!c.mask.empty() && c.mask(x, y) == 0) continue;
    kappa.push_back(m.curvature);
    abs_err.push_back(std::abs(m.d_px - g));
  }
  return Status::ok();
}

}  // namespace svslam::cli

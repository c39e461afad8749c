#include "eval/dem_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "map/dem_raster_check.hpp"

namespace svslam {

Result<DemScore> scoreDem(const map::DemRaster& est, const map::DemRaster& gt) {
  if (Status s = map::checkDemRaster(est, "estimated DEM"); !s) return s;
  if (Status s = map::checkDemRaster(gt, "ground-truth DEM"); !s) return s;
  if (std::abs(est.cell_m - gt.cell_m) > 1e-9 * std::max(est.cell_m, gt.cell_m))
    return Status::invalidArgument("DEM cell sizes differ: estimate " + std::to_string(est.cell_m) +
                                   " m, ground truth " + std::to_string(gt.cell_m) + " m");
  DemScore s;
  for (const float h : est.height_m) s.est_cells += std::isfinite(h) ? 1 : 0;

  std::vector<double> abs_err;
  double sum_e = 0, sum_e2 = 0;
  std::int64_t within = 0, stereo_covered = 0;
  for (int r = 0; r < gt.rows; ++r) {
    const int j = gt.j0 + gt.rows - 1 - r;
    for (int c = 0; c < gt.cols; ++c) {
      const std::size_t k = gt.index(c, r);
      const float h_gt = gt.height_m[k];
      const bool stereo = gt.count[k] > 0;  // false for NaN too
      const bool has_gt = std::isfinite(h_gt);
      if (!has_gt && !stereo) continue;
      int ec = 0, er = 0;
      float h_est = NAN, sigma_est = NAN;
      if (est.cellToPixel(gt.i0 + c, j, ec, er)) {
        h_est = est.height_m[est.index(ec, er)];
        sigma_est = est.sigma_m[est.index(ec, er)];
      }
      const bool has_est = std::isfinite(h_est);
      s.gt_stereo_cells += stereo ? 1 : 0;
      stereo_covered += (stereo && has_est) ? 1 : 0;
      if (!has_gt) continue;
      ++s.gt_cells;
      if (!has_est) continue;
      const double e = static_cast<double>(h_est) - static_cast<double>(h_gt);
      sum_e += e;
      sum_e2 += e * e;
      abs_err.push_back(std::abs(e));
      within += std::abs(e) <= 2.0 * static_cast<double>(sigma_est) ? 1 : 0;  // NaN: false
    }
  }
  s.common_cells = static_cast<std::int64_t>(abs_err.size());
  if (s.gt_cells > 0) s.coverage = static_cast<double>(s.common_cells) / s.gt_cells;
  if (s.gt_stereo_cells > 0)
    s.coverage_stereo = static_cast<double>(stereo_covered) / s.gt_stereo_cells;
  if (s.common_cells > 0) {
    const double n = static_cast<double>(s.common_cells);
    s.rmse_m = std::sqrt(sum_e2 / n);
    s.bias_m = sum_e / n;
    s.within_2sigma = static_cast<double>(within) / n;
    const std::size_t mid = abs_err.size() / 2;
    std::nth_element(abs_err.begin(), abs_err.begin() + mid, abs_err.end());
    s.median_abs_m = abs_err[mid];
    if (abs_err.size() % 2 == 0)  // the largest of the lower half sits before `mid`
      s.median_abs_m =
          0.5 * (s.median_abs_m + *std::max_element(abs_err.begin(), abs_err.begin() + mid));
  }
  return s;
}

}  // namespace svslam

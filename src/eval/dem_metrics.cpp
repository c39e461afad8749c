#include "eval/dem_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "map/dem_raster_check.hpp"

namespace svslam {
namespace {

// Median of v (mean of the middle two for an even count); v is reordered. v must not be empty.
double median(std::vector<double>& v) {
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  double m = v[mid];
  if (v.size() % 2 == 0)  // the largest of the lower half sits before `mid`
    m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
  return m;
}

// Squared horizontal distance from (px, py) to the segment a-b, m^2.
double segmentDistance2(double px, double py, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double dx = b.x() - a.x(), dy = b.y() - a.y();
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((px - a.x()) * dx + (py - a.y()) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  const double ex = a.x() + t * dx - px, ey = a.y() + t * dy - py;
  return ex * ex + ey * ey;
}

// Raster indices (dem.index) of the cells with a height whose centre is within half_width_m of
// the polyline, sorted, each once. Visits only each segment's grown bounding box.
std::vector<std::size_t> stripCells(const map::DemRaster& dem,
                                    const std::vector<Eigen::Vector3d>& path, double half_width_m) {
  std::vector<std::size_t> cells;
  const double w2 = half_width_m * half_width_m, cell = dem.cell_m;
  for (std::size_t s = 0; s < path.size(); ++s) {
    const Eigen::Vector3d& a = path[s];
    const Eigen::Vector3d& b = path[s + 1 < path.size() ? s + 1 : s];
    // Map indices of the cells whose centre (i + 0.5) cell_m lies in the grown box.
    const auto lo = [&](double v) { return std::ceil((v - half_width_m) / cell - 0.5); };
    const auto hi = [&](double v) { return std::floor((v + half_width_m) / cell - 0.5); };
    const double i_lo = std::max<double>(lo(std::min(a.x(), b.x())), dem.i0);
    const double i_hi = std::min<double>(hi(std::max(a.x(), b.x())), dem.i0 + dem.cols - 1.0);
    const double j_lo = std::max<double>(lo(std::min(a.y(), b.y())), dem.j0);
    const double j_hi = std::min<double>(hi(std::max(a.y(), b.y())), dem.j0 + dem.rows - 1.0);
    if (i_lo > i_hi || j_lo > j_hi) continue;  // the box misses the raster
    for (int j = static_cast<int>(j_lo); j <= static_cast<int>(j_hi); ++j) {
      for (int i = static_cast<int>(i_lo); i <= static_cast<int>(i_hi); ++i) {
        int c = 0, r = 0;
        if (!dem.cellToPixel(i, j, c, r)) continue;
        const std::size_t k = dem.index(c, r);
        if (!std::isfinite(dem.height_m[k])) continue;
        if (segmentDistance2((i + 0.5) * cell, (j + 0.5) * cell, a, b) <= w2) cells.push_back(k);
      }
    }
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  return cells;
}

}  // namespace

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
    s.median_abs_m = median(abs_err);
  }
  return s;
}

namespace {

// Least-squares plane z = a x + b y + c over the points q with (*use)[q] (all when use is null),
// centred for conditioning. False when fewer than 3 points or all on one line.
bool fitPlane(const std::vector<double>& x, const std::vector<double>& y,
              const std::vector<double>& z, const std::vector<char>* use, double& a, double& b,
              double& c) {
  double mx = 0, my = 0, mz = 0;
  std::size_t n = 0;
  for (std::size_t q = 0; q < x.size(); ++q) {
    if (use && !(*use)[q]) continue;
    mx += x[q];
    my += y[q];
    mz += z[q];
    ++n;
  }
  if (n < 3) return false;
  mx /= static_cast<double>(n);
  my /= static_cast<double>(n);
  mz /= static_cast<double>(n);
  double sxx = 0, sxy = 0, syy = 0, sxz = 0, syz = 0;
  for (std::size_t q = 0; q < x.size(); ++q) {
    if (use && !(*use)[q]) continue;
    const double dx = x[q] - mx, dy = y[q] - my, dz = z[q] - mz;
    sxx += dx * dx;
    sxy += dx * dy;
    syy += dy * dy;
    sxz += dx * dz;
    syz += dy * dz;
  }
  // Normal equations of the centred fit dz = a dx + b dy; singular when the centres are on a line.
  const double det = sxx * syy - sxy * sxy;
  if (!(det > 1e-12 * (sxx + syy) * (sxx + syy))) return false;  // scale-free test
  a = (syy * sxz - sxy * syz) / det;
  b = (sxx * syz - sxy * sxz) / det;
  c = mz - a * mx - b * my;
  return true;
}

}  // namespace

Result<PathStripScore> scorePathStrip(const map::DemRaster& dem,
                                      const std::vector<Eigen::Vector3d>& path_map,
                                      double half_width_m, double surface_band_m) {
  if (Status s = map::checkDemRaster(dem, "DEM"); !s) return s;
  if (std::isnan(surface_band_m))
    return Status::invalidArgument("surface band must not be NaN (<= 0: no surface figures)");
  if (!std::isfinite(half_width_m) || half_width_m <= 0)
    return Status::invalidArgument("path strip half-width must be finite and > 0, got " +
                                   std::to_string(half_width_m) + " m");
  PathStripScore s;
  for (std::size_t k = 0; k < path_map.size(); ++k) {
    if (!path_map[k].allFinite())
      return Status::invalidArgument("path point " + std::to_string(k) + " is not finite");
    if (k > 0) s.path_length_m += (path_map[k] - path_map[k - 1]).head<2>().norm();
  }
  const std::vector<std::size_t> cells = stripCells(dem, path_map, half_width_m);
  s.strip_cells = static_cast<std::int64_t>(cells.size());
  if (cells.empty()) return s;

  // Cell centres (x, y) and heights, m.
  const std::size_t n = cells.size();
  std::vector<double> x(n), y(n), z(n), sigma;
  double mz = 0;
  for (std::size_t q = 0; q < n; ++q) {
    const auto c = static_cast<int>(cells[q] % static_cast<std::size_t>(dem.cols));
    const auto r = static_cast<int>(cells[q] / static_cast<std::size_t>(dem.cols));
    x[q] = (dem.i0 + c + 0.5) * dem.cell_m;
    y[q] = (dem.j0 + dem.rows - 1 - r + 0.5) * dem.cell_m;
    z[q] = dem.height_m[cells[q]];
    if (std::isfinite(dem.sigma_m[cells[q]])) sigma.push_back(dem.sigma_m[cells[q]]);
    mz += z[q];
  }
  mz /= static_cast<double>(n);
  double szz = 0;
  for (std::size_t q = 0; q < n; ++q) szz += (z[q] - mz) * (z[q] - mz);
  s.height_std_m = std::sqrt(szz / n);
  if (!sigma.empty()) s.median_sigma_m = median(sigma);

  if (!fitPlane(x, y, z, nullptr, s.plane_a, s.plane_b, s.plane_c)) return s;
  std::vector<double> abs_r(n);
  std::vector<char> keep(n);  // road surface: |r| <= surface_band_m (below)
  double sum_r2 = 0;
  for (std::size_t q = 0; q < n; ++q) {
    const double r = z[q] - (s.plane_a * x[q] + s.plane_b * y[q] + s.plane_c);
    sum_r2 += r * r;
    abs_r[q] = std::abs(r);
    keep[q] = abs_r[q] <= surface_band_m;
  }
  s.plane_residual_std_m = std::sqrt(sum_r2 / n);
  const std::size_t rank = static_cast<std::size_t>(std::ceil(0.95 * n));  // 1-based, >= 1
  std::nth_element(abs_r.begin(), abs_r.begin() + (rank - 1), abs_r.end());
  s.plane_residual_p95_abs_m = abs_r[rank - 1];
  double sum_h = 0;
  for (const Eigen::Vector3d& p : path_map)
    sum_h += p.z() - (s.plane_a * p.x() + s.plane_b * p.y() + s.plane_c);
  s.camera_height_above_plane_m = sum_h / static_cast<double>(path_map.size());

  // The road surface: the cells within surface_band_m of the plane (what stands on the road, a
  // car or a post, or a gross error, is not road), a plane refitted to them and their residuals.
  if (!(surface_band_m > 0)) return s;
  double a = 0, b = 0, c = 0;
  if (!fitPlane(x, y, z, &keep, a, b, c)) return s;
  double sum_s2 = 0;
  for (std::size_t q = 0; q < n; ++q) {
    if (!keep[q]) continue;
    const double r = z[q] - (a * x[q] + b * y[q] + c);
    sum_s2 += r * r;
    ++s.surface_cells;
  }
  s.off_surface_cells = static_cast<std::int64_t>(n) - s.surface_cells;
  s.surface_residual_std_m = std::sqrt(sum_s2 / static_cast<double>(s.surface_cells));
  return s;
}

std::vector<Eigen::Vector3d> dropPathStart(const std::vector<Eigen::Vector3d>& path_map,
                                           double min_ahead_m) {
  if (!(min_ahead_m > 0)) return path_map;
  double walked = 0;  // horizontal arc length up to path_map[k - 1], m
  for (std::size_t k = 1; k < path_map.size(); ++k) {
    const double step = (path_map[k] - path_map[k - 1]).head<2>().norm();
    if (walked + step > min_ahead_m) {  // a cut on a vertex starts at that vertex, once
      const double t = (min_ahead_m - walked) / step;
      std::vector<Eigen::Vector3d> out{path_map[k - 1] + t * (path_map[k] - path_map[k - 1])};
      out.insert(out.end(), path_map.begin() + static_cast<std::ptrdiff_t>(k), path_map.end());
      return out;
    }
    walked += step;
  }
  return {};
}

}  // namespace svslam

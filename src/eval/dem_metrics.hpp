#pragma once
// Accuracy and coverage of an estimated elevation raster against a ground-truth one.
//
// Both rasters are windows of the same map grid (dem_raster.hpp): cells are paired by their map
// indices (i, j), so the two windows may have any origin (i0, j0) and size; only the cell size
// must agree. A cell "has a height" when its height is finite. The observed area is the set of
// ground-truth cells with a height; "common" cells have a height in both rasters. Errors are
// e = est - gt, metres. Figures over an empty set are NaN (JSON null).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/status.hpp"
#include "map/dem_raster.hpp"

namespace svslam {

struct DemScore {
  std::int64_t gt_cells = 0;      // ground-truth cells with a height (the observed area)
  std::int64_t est_cells = 0;     // estimated cells with a height (in the whole estimate)
  std::int64_t common_cells = 0;  // cells with a height in both
  double rmse_m = NAN;            // sqrt(mean e^2) over common cells, m
  double median_abs_m = NAN;      // median |e| over common cells (mean of the middle two), m
  double bias_m = NAN;            // mean e over common cells, m
  double coverage = NAN;          // common_cells / gt_cells, [0, 1]
  // Share of common cells with |e| <= 2 sigma_est (a NaN sigma counts as outside), [0, 1].
  double within_2sigma = NAN;
  // Ground-truth cells whose count band is > 0: the ground truth uses that band for the number
  // of frames in which the cell was seen by both cameras.
  std::int64_t gt_stereo_cells = 0;
  double coverage_stereo = NAN;  // share of gt_stereo_cells with an estimated height, [0, 1]
};

// Errors (invalidArgument, naming the raster): a malformed raster (checkDemRaster) or
// different cell sizes (relative difference > 1e-9).
Result<DemScore> scoreDem(const map::DemRaster& est, const map::DemRaster& gt);

// Flatness of the ground a vehicle drove over: the "path strip" is the set of cells with a
// height whose centre (x, y) lies within half_width_m (horizontal distance, m) of the polyline
// of the path's (x, y). A plane z = a x + b y + c is fitted to the strip's heights by least
// squares; its residuals are the flatness without the road's slope. Figures over an empty set,
// or plane figures when the strip does not fix a plane (< 3 cells, or all on one line), are NaN.
struct PathStripScore {
  std::int64_t strip_cells = 0;  // cells of the strip with a height
  double path_length_m = 0;      // horizontal length of the polyline, m
  double height_std_m = NAN;     // standard deviation (1/n) of the strip's heights, m
  double plane_a = NAN, plane_b = NAN, plane_c = NAN;  // z = a x + b y + c (m/m, m/m, m)
  double plane_residual_std_m = NAN;                   // sqrt(mean r^2), r = height - plane, m
  double plane_residual_p95_abs_m = NAN;               // 95th percentile of |r| (nearest rank), m
  double median_sigma_m = NAN;  // median sigma band over the strip (finite ones), m
  // Mean over the path points of z - plane(x, y), m: the camera's height above the road.
  double camera_height_above_plane_m = NAN;
  // The road surface: the strip's cells within surface_band_m of the plane (what stands on the
  // road, a vehicle or a post, and gross errors are not road); a plane refitted to them and the
  // RMS of their residuals, m. NaN / 0 when surface_band_m <= 0 or the cells fix no plane.
  std::int64_t surface_cells = 0;
  std::int64_t off_surface_cells = 0;  // strip cells farther than surface_band_m from the plane
  double surface_residual_std_m = NAN;
};

// path_map: positions in the map frame (x, y horizontal, z up), m, in driving order.
// Errors (invalidArgument): a malformed raster, half_width_m not finite or <= 0, surface_band_m
// NaN, a non-finite path point. Cost: the cells of each segment's bounding box grown by
// half_width_m.
Result<PathStripScore> scorePathStrip(const map::DemRaster& dem,
                                      const std::vector<Eigen::Vector3d>& path_map,
                                      double half_width_m, double surface_band_m = 0.3);

// The path without its first min_ahead_m metres of horizontal length: starts at the point of
// the polyline at that arc length (interpolated, z too), then the later points. Empty when the
// path is not longer; the whole path when min_ahead_m <= 0.
std::vector<Eigen::Vector3d> dropPathStart(const std::vector<Eigen::Vector3d>& path_map,
                                           double min_ahead_m);

}  // namespace svslam

#pragma once
// Accuracy and coverage of an estimated elevation raster against a ground-truth one.
//
// Both rasters are windows of the same map grid (dem_raster.hpp): cells are paired by their map
// indices (i, j), so the two windows may have any origin (i0, j0) and size; only the cell size
// must agree. A cell "has a height" when its height is finite. The observed area is the set of
// ground-truth cells with a height; "common" cells have a height in both rasters. Errors are
// e = est - gt, metres. Figures over an empty set are NaN (JSON null).
#include <cstdint>

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

}  // namespace svslam

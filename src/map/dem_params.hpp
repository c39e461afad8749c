#pragma once
// Parameters of the elevation map (seed 001 sec 5.2): a DEM z = f(x, y) and an orthoimage on a
// regular grid of the map frame (map_frame.hpp), fused from dense stereo after every estimator
// update. Units in the names; defaults are the values of config/svslam.yaml's `map:` section.
#include <array>
#include <cmath>

#include "core/status.hpp"

namespace svslam::map {

struct DemParams {
  double cell_m = 0.1;  // grid cell side, m, (0.001, 100]
  // Gravity direction (unit vector, pointing down) in the first left camera's frame
  // (x right, y down, z forward). [0, 0, 1]: a camera looking straight down (blimp);
  // [0, 1, 0]: a level, forward-looking camera (car).
  std::array<double, 3> gravity_in_first_camera{0.0, 0.0, 1.0};
  int tile_cells = 64;        // tile side in cells (tiles are allocated on demand), [8, 1024]
  double max_range_m = 60.0;  // points farther from the camera are not fused, m, > 0
  // Points higher than this above the camera centre (map z) are not fused: a ground vehicle
  // maps the ground, not the street lamps and branches over it. m, finite; default: no limit.
  double max_height_above_camera_m = 1e6;
  double min_disparity_px = 1.0;  // smaller disparities (far, imprecise) are not fused, px, > 0
  // Mahalanobis gate (chi-square, 1 dof) of a point's height against the cell's estimate; a
  // point beyond it has its variance inflated to sit on the gate instead of dragging the cell.
  double gate_chi2 = 9.0;  // (0, 1e6]
  // A cell whose estimate most of a frame's points (in that cell) reject has its independent
  // variance multiplied by this factor before the frame is fused: an object that has moved away
  // (a car that was ahead) leaves a cell that later frames would otherwise only nudge; after k
  // such frames its weight is 1 / factor^k. One frame of outliers moves a cell little. [1, 1e3];
  // 1 disables it.
  double reject_variance_factor = 2.0;
  // Height standard deviation every cell keeps at least: the model error of dense stereo on a
  // relief (window smoothing, the cell's own slope), m, >= 0.
  double min_sigma_m = 0.01;
  int max_tiles = 4096;  // bound on the tiles in memory (64 x 64 cells x 12 B = 48 KiB each)
  // Bound on the cells of the map written as one raster (bounding box of the tiles, 13 B a
  // cell), millions, [1, 4096]: a diverged trajectory spreads a few tiles over kilometres.
  int max_raster_mcells = 64;
  // Keep, per cell, the latest fusion that wrote into it (DemTile::sources, 4 B more a cell),
  // so the map can be re-placed when past poses are corrected (dem_replacer.hpp). Not a config
  // key: `svslam run` sets it when loop closing is on.
  bool keep_cell_sources = false;

  Status validate() const;
};

}  // namespace svslam::map

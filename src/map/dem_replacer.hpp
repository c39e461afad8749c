#pragma once
// Re-placing the elevation map when past poses are corrected (loop closing; seed 001 sec 5.2's
// map, issue "loop closing": the DEM follows the corrected trajectory).
//
// Input: a map fused with DemParams::keep_cell_sources (each cell knows the latest fusion s that
// wrote into it) and, per fusion s, the world-frame correction C_s that moves a
// pose estimated then into the corrected frame (T_corrected = C_s T_online; world = first left
// camera, map_frame.hpp). Each cell with data is a point at its centre and height,
//     p_map = ((i + 1/2) cell_m, (j + 1/2) cell_m, h),
// moved rigidly with its source's correction,
//     p_map' = R_map_world C_s R_map_world^T p_map,
// and splatted bilinearly into the output grid: at u = x'/cell_m - 1/2, v = y'/cell_m - 1/2 the
// four cells around (u, v) receive the bilinear weights b (sum 1) of the point. Per output cell,
// over the points that reach it (w = 1 / var_indep of the source cell):
//     height    = sum(b w h') / sum(b w)
//     var_indep = sum(b) / sum(b w)        (a b-weighted harmonic mean: interpolating adds no
//                                           information, a whole-cell shift keeps var_indep)
//     var_pose  = sum(b var_pose) / sum(b),  count = round(sum(b count) / sum(b)),
//     luminance = sum(b count lum) / sum(b count).
// A cell whose points' weights sum(b) fall below min_coverage stays empty (the border of the
// map, where only part of a cell's neighbourhood was measured). A correction that is a whole
// number of cells in x and y reproduces each moved cell exactly (height + dz); the identity
// reproduces the map. The pose part of the sigma is kept as it was (the corrected poses are no
// less certain than the online ones; conservative). A cell mixes what every pass over it
// measured; it moves with the last pass only, so a cell seen on two passes with different drift
// keeps part of the difference. The last pass: neighbouring cells then share one stretch of
// trajectory and move together (CHANGELOG.md: the heaviest single frame instead).
//
// Memory: while it runs, 32 B of accumulator per cell of every output tile touched (twice the
// map's 16 B a cell with sources), freed at the end.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/status.hpp"
#include "map/dem_map.hpp"
#include "map/dem_params.hpp"

namespace svslam::map {

struct DemReplacerParams {
  // Output cells whose summed bilinear weight is below this stay empty, [0.01, 1]. 0.5 keeps the
  // map's extent under a sub-cell move (an edge cell half covered is kept).
  double min_coverage = 0.5;
  Status validate() const;
};

struct DemReplaceStats {
  std::int64_t cells_in = 0;         // cells with data in the input map
  std::int64_t cells_out = 0;        // cells with data in the output map
  std::int64_t cells_no_source = 0;  // input cells without a source or correction (unmoved)
  std::int64_t cells_no_tile = 0;    // points whose output tile would exceed max_tiles
  double max_shift_m = 0.0;          // largest horizontal move of a cell, m
  double rms_shift_m = 0.0;          // RMS horizontal move over the input cells, m
  double rms_dz_m = 0.0;             // RMS vertical move over the input cells, m
};

class DemReplacer {
 public:
  DemReplacer(const DemReplacerParams& params, const Eigen::Matrix3d& R_map_world);
  const Status& initStatus() const { return init_status_; }

  // Re-places `in` into `out` (cleared first; same cell_m and tile_cells, its own max_tiles
  // applies). C_world_by_seq[s]: fusion s's correction; a cell whose source is missing or out
  // of range stays where it was (counted). Errors: uninitialised replacer, a map that kept no
  // cell sources, different grids, a correction that is not a finite rigid transform.
  Status process(const DemMap& in, const std::vector<Eigen::Isometry3d>& C_world_by_seq,
                 DemMap& out, DemReplaceStats& stats);

 private:
  struct Acc {  // per output cell
    double sum_bw = 0.0, sum_bwh = 0.0;
    float sum_b = 0.0f, sum_bvp = 0.0f, sum_bn = 0.0f, sum_bnl = 0.0f;
  };
  DemReplacerParams params_;
  Eigen::Matrix3d R_map_world_;
  Status init_status_;
};

}  // namespace svslam::map

#pragma once
// Storage of the elevation map: square tiles of DemParams::tile_cells^2 cells, allocated when a
// point first falls in them (the map grows with the flight; no fixed square), 12 bytes a cell.
//
// A cell holds the fusion of every height measurement that fell in it (dem_fuser.hpp):
//   height_m      inverse-variance weighted mean of the heights, weights w = 1 / var_indep;
//   sigma_indep   1 / sqrt(sum w): the independent (disparity) part of the height's error;
//   sigma_pose    root mean square over the points of the pose part of their height sigma. Pose
//                 errors are shared by every point of a frame and drift slowly from frame to
//                 frame, so this part is not divided down by the number of points;
//   count         points fused (saturates at 65535);
//   luminance     mean grey level of the points, 8.8 fixed point.
// Reported standard deviation: sqrt(sigma_indep^2 + sigma_pose^2 + min_sigma_m^2).
//
// Moving the map when past poses are corrected (loop closing): every tile records the range of
// fusion sequence numbers (frames) that wrote into it, and with DemParams::keep_cell_sources
// every cell the latest fusion that wrote into it, so each cell can be re-placed by the
// correction of the pose of the last pass over it (dem_replacer.hpp).
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "core/status.hpp"
#include "map/dem_params.hpp"
#include "map/dem_raster.hpp"

namespace svslam::map {

// Standard deviations stored as a 16-bit logarithm: sigma = 2^(code / 1024 - 20) m, code >= 1
// (2^-20 m .. 2^44 m, 0.07 % steps); code 0 is exactly 0.
std::uint16_t encodeSigma(double sigma_m);
double decodeSigma(std::uint16_t code);
// decodeSigma(code)^2 as a float, from a table (no exp2 on the per-cell path).
float decodeVariance(std::uint16_t code);
// encodeSigma(sqrt(var_m2)), without the square root.
std::uint16_t encodeVariance(double var_m2);

struct DemCell {
  float height_m = 0.0f;
  std::uint16_t sigma_indep = 0;  // encodeSigma
  std::uint16_t sigma_pose = 0;   // encodeSigma
  std::uint16_t count = 0;        // 0: no data
  std::uint16_t luminance_8_8 = 0;
};
static_assert(sizeof(DemCell) == 12, "a cell is 12 bytes");

// One frame's measurement of a cell, summed over its points (the fuser's accumulator).
struct CellMeasurement {
  double sum_w = 0.0;         // sum of 1 / var_indep, 1/m^2
  double sum_wh = 0.0;        // sum of h / var_indep, 1/m
  double sum_var_pose = 0.0;  // sum of the points' pose variance, m^2
  std::uint32_t count = 0;
  std::uint32_t sum_luminance = 0;  // grey levels
  // Points of `count` that the Mahalanobis gate found inconsistent with the cell (DemFuser).
  std::uint32_t gated = 0;
};

struct DemTile {
  int ti = 0, tj = 0;           // tile index: cells [ti n, (ti + 1) n) x [tj n, (tj + 1) n)
  std::vector<DemCell> cells;   // n x n, row-major, row 0 = smallest y
  // With keep_cell_sources, n x n as cells: the latest fusion (DemFuser sequence number) that
  // wrote into each cell, -1 for none; else empty.
  std::vector<std::int32_t> sources;
  std::int64_t first_seq = -1;  // fusion sequence numbers that wrote here
  std::int64_t last_seq = -1;
  std::int64_t last_t_ns = 0;  // time of the last frame that wrote here
};

class DemMap {
 public:
  explicit DemMap(const DemParams& params);
  const Status& initStatus() const { return init_status_; }
  const DemParams& params() const { return params_; }
  int tileCells() const { return params_.tile_cells; }

  // The cell (i, j), or null when its tile does not exist.
  const DemCell* cell(int i, int j) const;
  // Height (m) and its total standard deviation (m) of cell (i, j); false when it has no data.
  bool estimate(int i, int j, double& height_m, double& sigma_m) const;
  // Total variance (m^2) of a cell with data.
  float variance(const DemCell& c) const {
    return decodeVariance(c.sigma_indep) + decodeVariance(c.sigma_pose) + min_var_;
  }
  // Fuses one frame's measurement into cell (i, j), creating its tile when needed. False when
  // the tile would exceed params.max_tiles (nothing written).
  bool fuse(int i, int j, const CellMeasurement& m, std::int64_t seq, std::int64_t t_ns);

  // The tile (ti, tj), created when missing; null when that would exceed params.max_tiles.
  DemTile* tileForWrite(int ti, int tj);
  // Fuses one frame's measurement into a cell (nothing when it holds no point). When most of
  // the measurement's points were gated (2 gated > count), the cell's independent variance is
  // first multiplied by reject_variance_factor (DemParams).
  static void fuseCell(DemCell& c, const CellMeasurement& m, double reject_variance_factor);
  // Records that fusion `seq` wrote into cell k (index into t.cells), when the tile keeps
  // sources.
  static void recordSource(DemTile& t, std::size_t k, std::int64_t seq) {
    if (!t.sources.empty()) t.sources[k] = static_cast<std::int32_t>(seq);
  }
  // Records that fusion number `seq` (frame time t_ns) wrote into `t`.
  static void touch(DemTile& t, std::int64_t seq, std::int64_t t_ns);
  // Tile of cell index i (floor division).
  int tileOf(int i) const;
  const std::vector<DemTile>& tiles() const { return tiles_; }
  const DemTile* tile(int ti, int tj) const;
  int numTiles() const { return static_cast<int>(tiles_.size()); }
  std::size_t bytes() const;  // memory held by the cells (and their sources), bytes

  // The whole map (bounding box of the tiles) as a north-up raster; outOfRange (out empty)
  // when that box holds more than max_raster_mcells million cells.
  Status toRaster(DemRaster& out) const;
  // One tile as an n x n raster.
  void tileRaster(const DemTile& tile, DemRaster& out) const;
  // Tile (ti, tj) as an n x n raster with no data (NaN heights and sigmas, count and
  // luminance 0), whether the map has it or not.
  void emptyTileRaster(int ti, int tj, DemRaster& out) const;
  // Removes every tile (the map restarts empty; their memory is freed).
  void clear();

 private:
  static std::uint64_t key(int ti, int tj) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ti)) << 32) |
           static_cast<std::uint32_t>(tj);
  }
  void fillRaster(const DemTile& tile, DemRaster& out) const;
  // Reported standard deviation of a cell with data, m (the header's formula, in double).
  double totalSigma(const DemCell& c) const;

  DemParams params_;
  Status init_status_;
  float min_var_ = 0.0f;  // min_sigma_m^2
  std::vector<DemTile> tiles_;
  std::unordered_map<std::uint64_t, int> index_;  // key(ti, tj) -> tiles_ slot
  // Cache of the last tile looked up (points arrive in runs within one tile).
  mutable std::uint64_t last_key_ = ~0ull;
  mutable int last_slot_ = -1;
};

}  // namespace svslam::map

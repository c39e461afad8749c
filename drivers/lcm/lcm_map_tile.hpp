#pragma once
// One tile of the elevation map on the wire (svslam_lcm.map_tile_t, lcm/map_tile_t.lcm).
// In memory a tile is a map::DemRaster of n x n cells, north-up (row 0 = largest y), with
// i0 = tile_i * n and j0 = tile_j * n; on the wire its rows run the other way (row 0 = smallest
// y). encodeMapTile and decodeMapTile flip the rows, so a round trip gives the raster back
// (counts saturated to [0, 32767] and rounded; cell_m, heights and sigmas exact).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/status.hpp"
#include "core/time.hpp"
#include "map/dem_raster.hpp"

namespace svslam::drivers {

inline constexpr int kMaxMapTileCells = 1024;  // largest cells_per_side on the wire

struct MapTileMessage {
  TimeNs t_ns = 0;       // capture time of the frame of the tile's last update
  std::int64_t seq = 0;  // message sequence number
  int tile_i = 0, tile_j = 0;
  map::DemRaster tile;  // n x n cells, north-up, i0 = tile_i * n, j0 = tile_j * n
};

// Encodes `tile` (exactly n x n cells, 1 <= n <= kMaxMapTileCells, every array of n * n
// elements, cell_m finite and > 0, i0 = tile_i * n, j0 = tile_j * n) into the bytes of a
// map_tile_t. Counts are rounded and saturated to [0, 32767] (NaN: 0). Errors name the problem.
Status encodeMapTile(const map::DemRaster& tile, int tile_i, int tile_j, std::int64_t t_ns,
                     std::int64_t seq, std::vector<std::uint8_t>& out);

// Decodes untrusted bytes of a map_tile_t: kCorruptData on a wrong type hash, a size that is not
// the one the header implies, cells_per_side outside [1, kMaxMapTileCells], num_cells != n * n,
// a non-finite or non-positive cell_m, a negative count, or a tile index whose cells overflow
// int. `out` is untouched on error.
Status decodeMapTile(const std::uint8_t* data, std::size_t size, MapTileMessage& out);

}  // namespace svslam::drivers

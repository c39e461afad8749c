// map_tile_t <-> map::DemRaster (lcm_map_tile.hpp).
#include "drivers/lcm/lcm_map_tile.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <exception>
#include <string>
#include <utility>

#include "svslam_lcm/map_tile_t.hpp"

namespace svslam::drivers {
namespace {

constexpr const char* kWhat = "svslam_lcm.map_tile_t";
// Bytes before the arrays: hash 8, t_ns 8, seq 8, tile_i/j 8, n 4, cell_m 8, num_cells 4.
constexpr std::size_t kHeaderBytes = 48;
constexpr std::size_t kCellBytes = 4 + 4 + 2 + 1;  // height, sigma, count, luminance

std::int32_t readBigEndianI32(const std::uint8_t* p) {
  const std::uint32_t u = (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) |
                          (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
  return static_cast<std::int32_t>(u);
}

// Cells [tile * n, (tile + 1) * n) fit in int.
bool indexFits(int tile, int n) {
  const long long first = static_cast<long long>(tile) * n;
  return first >= INT_MIN && first + n - 1 <= INT_MAX;
}

Status bad(const std::string& m) { return Status::invalidArgument("map tile: " + m); }
Status corrupt(const std::string& m) { return Status::corruptData(std::string(kWhat) + ": " + m); }

}  // namespace

Status encodeMapTile(const map::DemRaster& tile, int tile_i, int tile_j, std::int64_t t_ns,
                     std::int64_t seq, std::vector<std::uint8_t>& out) {
  const int n = tile.cols;
  if (n < 1 || n > kMaxMapTileCells || tile.rows != n)
    return bad("raster is " + std::to_string(tile.cols) + " x " + std::to_string(tile.rows) +
               " cells; a tile is n x n with 1 <= n <= " + std::to_string(kMaxMapTileCells));
  const std::size_t cells = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  if (tile.height_m.size() != cells || tile.sigma_m.size() != cells || tile.count.size() != cells ||
      tile.luminance.size() != cells)
    return bad("arrays do not hold n * n = " + std::to_string(cells) + " cells");
  if (!(std::isfinite(tile.cell_m) && tile.cell_m > 0.0))
    return bad("cell_m must be finite and > 0");
  if (!indexFits(tile_i, n) || !indexFits(tile_j, n))
    return bad("tile index (" + std::to_string(tile_i) + ", " + std::to_string(tile_j) +
               ") is out of the map's int range");
  if (tile.i0 != tile_i * n || tile.j0 != tile_j * n)
    return bad("raster origin (i0 " + std::to_string(tile.i0) + ", j0 " + std::to_string(tile.j0) +
               ") is not tile (" + std::to_string(tile_i) + ", " + std::to_string(tile_j) + ") x " +
               std::to_string(n) + " cells");
  svslam_lcm::map_tile_t m;
  m.t_ns = t_ns;
  m.seq = seq;
  m.tile_i = tile_i;
  m.tile_j = tile_j;
  m.cells_per_side = n;
  m.cell_m = tile.cell_m;
  m.num_cells = static_cast<std::int32_t>(cells);
  m.height_m.resize(cells);
  m.sigma_m.resize(cells);
  m.count.resize(cells);
  m.luminance.resize(cells);
  for (int r = 0; r < n; ++r) {  // wire row r = raster row n - 1 - r (north-up -> south-up)
    for (int c = 0; c < n; ++c) {
      const std::size_t w = static_cast<std::size_t>(r) * n + c;
      const std::size_t k = tile.index(c, n - 1 - r);
      m.height_m[w] = tile.height_m[k];
      m.sigma_m[w] = tile.sigma_m[k];
      const float cnt = tile.count[k];
      m.count[w] = std::isnan(cnt)
                       ? std::int16_t{0}
                       : static_cast<std::int16_t>(std::lround(std::clamp(cnt, 0.0f, 32767.0f)));
      m.luminance[w] = tile.luminance[k];
    }
  }
  const int size = m.getEncodedSize();
  out.resize(static_cast<std::size_t>(size));
  if (m.encode(out.data(), 0, size) != size) return bad("LCM encode failed");
  return Status::ok();
}

Status decodeMapTile(const std::uint8_t* data, std::size_t size, MapTileMessage& out) {
  if (data == nullptr || size < kHeaderBytes || size > static_cast<std::size_t>(INT_MAX))
    return corrupt(std::to_string(size) + " bytes is not a message");
  std::int64_t hash = 0;
  if (__int64_t_decode_array(data, 0, 8, &hash, 1) != 8 ||
      hash != svslam_lcm::map_tile_t::getHash())
    return corrupt("type hash mismatch (another type or garbage)");
  const std::int32_t n = readBigEndianI32(data + 32);
  const std::int32_t num_cells = readBigEndianI32(data + 44);
  if (n < 1 || n > kMaxMapTileCells)
    return corrupt("cells_per_side " + std::to_string(n) + " is outside [1, " +
                   std::to_string(kMaxMapTileCells) + "]");
  if (num_cells != n * n)
    return corrupt("num_cells " + std::to_string(num_cells) + " != cells_per_side^2 " +
                   std::to_string(n * n));
  const std::size_t cells = static_cast<std::size_t>(num_cells);
  if (size != kHeaderBytes + kCellBytes * cells)
    return corrupt(std::to_string(size) + " bytes, expected " +
                   std::to_string(kHeaderBytes + kCellBytes * cells) + " for " + std::to_string(n) +
                   " x " + std::to_string(n) + " cells");
  svslam_lcm::map_tile_t m;
  try {
    if (m.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size))
      return corrupt("decode failed");
  } catch (const std::exception& e) {
    return corrupt(std::string("decode failed (") + e.what() + ")");
  }
  if (!(std::isfinite(m.cell_m) && m.cell_m > 0.0)) return corrupt("cell_m must be finite and > 0");
  if (!indexFits(m.tile_i, n) || !indexFits(m.tile_j, n))
    return corrupt("tile index out of the map's int range");
  for (std::int16_t c : m.count)
    if (c < 0) return corrupt("negative count");
  MapTileMessage t;
  t.t_ns = m.t_ns;
  t.seq = m.seq;
  t.tile_i = m.tile_i;
  t.tile_j = m.tile_j;
  t.tile.cell_m = m.cell_m;
  t.tile.i0 = m.tile_i * n;
  t.tile.j0 = m.tile_j * n;
  t.tile.resize(n, n);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const std::size_t w = static_cast<std::size_t>(r) * n + c;
      const std::size_t k = t.tile.index(c, n - 1 - r);
      t.tile.height_m[k] = m.height_m[w];
      t.tile.sigma_m[k] = m.sigma_m[w];
      t.tile.count[k] = static_cast<float>(m.count[w]);
      t.tile.luminance[k] = m.luminance[w];
    }
  }
  out = std::move(t);
  return Status::ok();
}

}  // namespace svslam::drivers

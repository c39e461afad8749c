#pragma once
// A rectangular window of the elevation map, north-up, ready to be written as GeoTIFF/PNG or
// scored: row 0 is the row of largest y. Cell (i, j) of the map (map_frame.hpp) is at column
// c = i - i0 and row r = (j0 + rows - 1) - j; its centre is at x = (i + 0.5) cell_m,
// y = (j + 0.5) cell_m in the map frame. Geotransform of the raster (GDAL convention):
// [i0 * cell_m, cell_m, 0, (j0 + rows) * cell_m, 0, -cell_m].
#include <cmath>
#include <cstdint>
#include <vector>

namespace svslam::map {

struct DemRaster {
  double cell_m = 0.1;
  int i0 = 0, j0 = 0;      // map index of column 0 and of the bottom row (rows - 1)
  int cols = 0, rows = 0;  // size, cells
  // Row-major, rows x cols. NaN where the cell has no data.
  std::vector<float> height_m;          // mean height above the map origin (z up), m
  std::vector<float> sigma_m;           // height standard deviation, m
  std::vector<float> count;             // points fused into the cell (0 where no data)
  std::vector<std::uint8_t> luminance;  // mean grey level; 0 where no data

  std::size_t index(int col, int row) const {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(cols) +
           static_cast<std::size_t>(col);
  }
  // Column/row of map cell (i, j); false when outside the raster.
  bool cellToPixel(int i, int j, int& col, int& row) const {
    col = i - i0;
    row = j0 + rows - 1 - j;
    return col >= 0 && col < cols && row >= 0 && row < rows;
  }
  void resize(int c, int r) {
    cols = c;
    rows = r;
    const auto n = static_cast<std::size_t>(c) * static_cast<std::size_t>(r);
    height_m.assign(n, NAN);
    sigma_m.assign(n, NAN);
    count.assign(n, 0.0f);
    luminance.assign(n, 0);
  }
};

}  // namespace svslam::map

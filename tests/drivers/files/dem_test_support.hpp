#pragma once
// Rasters for the tests of the elevation map's files.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "map/dem_raster.hpp"

namespace svslam::test {

// A cols x rows raster with distinct heights, sigmas, counts and grey levels, NaN (no data) on
// every fifth cell.
inline map::DemRaster sampleDem(int cols, int rows, int i0, int j0, double cell_m = 0.2) {
  map::DemRaster r;
  r.cell_m = cell_m;
  r.i0 = i0;
  r.j0 = j0;
  r.resize(cols, rows);
  for (std::size_t k = 0; k < r.height_m.size(); ++k) {
    if (k % 5 == 3) continue;
    r.height_m[k] = 0.37f * static_cast<float>(k) - 2.0f + 1e-3f * static_cast<float>(k % 7);
    r.sigma_m[k] = 0.01f + 0.003f * static_cast<float>(k % 11);
    r.count[k] = static_cast<float>(1 + k % 13);
    r.luminance[k] = static_cast<std::uint8_t>(1 + (k * 37) % 255);
  }
  return r;
}

// Bitwise equality of two float bands (NaN equals NaN).
inline bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

}  // namespace svslam::test

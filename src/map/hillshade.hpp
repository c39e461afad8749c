#pragma once
// Shaded relief of an elevation raster (Horn 1981, the method of `gdaldem hillshade`), as an
// 8-bit grey picture for people.
//
// With the raster north-up (dem_raster.hpp: x east, y north, row 0 the row of largest y) and the
// 3 x 3 window of heights around a cell
//     a b c      (row above: north)
//     d e f
//     g h i      (row below: south)
// the gradient is  p = dz/dx = ((c + 2f + i) - (a + 2d + g)) / (8 cell_m),
//                  q = dz/dy = ((a + 2b + c) - (g + 2h + i)) / (8 cell_m),   both times z_factor.
// The unit normal is n = (-p, -q, 1) / sqrt(1 + p^2 + q^2); the unit vector towards the sun,
// azimuth A clockwise from north (y) and altitude h above the horizon, is
// s = (sin A cos h, cos A cos h, sin h). The shade is n . s clamped to [0, 1], written as
// 1 + round(254 * shade) in [1, 255]; 0 is "no data": a cell whose height is NaN or has a NaN
// or missing neighbour (the raster's border cells). A flat cell at the defaults gives 181.
#include <cstdint>
#include <vector>

#include "core/status.hpp"
#include "map/dem_raster.hpp"

namespace svslam::map {

struct HillshadeParams {
  double azimuth_deg = 315.0;  // sun azimuth, clockwise from north (y), degrees, finite
  double altitude_deg = 45.0;  // sun altitude above the horizon, degrees, [0, 90]
  double z_factor = 1.0;       // heights are multiplied by this (metres vs cell metres), > 0
  Status validate() const;
};

// rows x cols grey levels, row-major like the raster. Errors: a malformed raster
// (checkDemRaster) or bad parameters, as invalidArgument.
Result<std::vector<std::uint8_t>> hillshade(const DemRaster& dem,
                                            const HillshadeParams& params = {});

}  // namespace svslam::map

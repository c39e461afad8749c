#pragma once
// The elevation map's files (docs/map.md "Files"):
//   dem.tif             GeoTIFF, 3 float32 bands: 1 height_m, 2 sigma_m (height standard
//                       deviation), 3 count (points fused); NaN = no data on every band.
//   ortho.tif           GeoTIFF, 1 uint8 band: mean grey level; 0 = no data.
//   ortho.png           the same grey levels as an 8-bit PNG (no georeference).
//   dem_hillshade.png   shaded relief of the heights (map/hillshade.hpp), 8-bit PNG.
//
// Georeference of the GeoTIFFs (map/dem_raster.hpp): north-up, pixel-is-area, geotransform
// [x0 + i0 cell_m, cell_m, 0, y0 + (j0 + rows) cell_m, 0, -cell_m], metres.
//  - Without a GeoOrigin: x0 = y0 = 0, coordinates of the map frame, in a local engineering CRS
//    (LOCAL_CS "svslam map frame (origin: first left camera, z up)", metre); heights as stored.
//  - With a GeoOrigin (the WGS 84 position of the map origin): the CRS is WGS 84 / UTM of the
//    origin's longitude (zone 1-60 by 6 degrees, north or south by the latitude's sign; the
//    Norway/Svalbard exceptions are not applied), map x is taken as UTM easting and map y as UTM
//    northing (no rotation: the caller makes the map frame's x point east), (x0, y0) = the
//    origin's easting and northing, and every height is stored as height_m + alt_m. The origin
//    is also kept in the metadata (SVSLAM_ORIGIN_EASTING_M, _NORTHING_M, _ALT_M, _LAT_DEG,
//    _LON_DEG), so that readDemGeoTiff gives back map-frame coordinates.
//
// Every writer is atomic: it writes a temporary beside `path` (path + ".tmp." + pid, or
// path + ".tmp" for the PNGs) and renames it over `path`. On any failure the temporary is
// removed, a previous file at `path` is left as it was, and the error (ioError, or
// invalidArgument for a bad raster or origin) names `path` and GDAL's or the system's reason.
// GDAL prints nothing on stderr: its messages go into the Status.
#include <string>

#include "core/status.hpp"
#include "map/dem_raster.hpp"

namespace svslam::drivers {

// WGS 84 position of the map origin (the first left camera centre).
struct GeoOrigin {
  double lat_deg = 0;  // latitude, degrees, [-80, 84] (the UTM range)
  double lon_deg = 0;  // longitude, degrees, [-180, 180]
  double alt_m = 0;    // ellipsoidal height of the origin, m, finite
};

// dem.tif: heights, sigmas and counts of `dem` (which must hold at least one cell).
Status writeDemGeoTiff(const std::string& path, const map::DemRaster& dem,
                       const GeoOrigin* geo = nullptr);
// ortho.tif: dem.luminance (rows x cols values), nodata 0.
Status writeOrthoTiff(const std::string& path, const map::DemRaster& dem,
                      const GeoOrigin* geo = nullptr);
// ortho.png: dem.luminance as 8-bit grey, row 0 = north (PNG whatever the extension).
Status writeOrthoPng(const std::string& path, const map::DemRaster& dem);
// dem_hillshade.png: hillshade(dem) with the default sun (map/hillshade.hpp), 8-bit grey.
Status writeHillshadePng(const std::string& path, const map::DemRaster& dem);

// Reads a dem.tif (or any north-up GeoTIFF with 3 bands in that order, square cells): cell_m =
// the geotransform's pixel width; i0 = round(x_left / cell_m), j0 = round(y_top / cell_m) - rows
// after removing the SVSLAM_ORIGIN_* offsets when present (and alt_m from the heights). Bands
// other than float32 are converted; luminance is all 0 (not in this file).
// Errors: notFound (no file), invalidArgument (a directory), corruptData naming the file for a
// file that is not a GeoTIFF, has another band count, no geotransform, a rotated or south-up
// geotransform, non-square cells, or more than 2^28 cells.
Result<map::DemRaster> readDemGeoTiff(const std::string& path);

}  // namespace svslam::drivers

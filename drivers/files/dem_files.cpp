// Writers of the elevation map's files (dem_files.hpp); the reader is in dem_files_read.cpp.
#include "drivers/files/dem_files.hpp"

#include <cpl_string.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <utility>
#include <vector>

#include "drivers/files/file_bytes.hpp"
#include "drivers/files/gdal_support.hpp"
#include "map/dem_raster_check.hpp"
#include "map/hillshade.hpp"

namespace svslam::drivers {

namespace {

constexpr const char* kLocalCs = "svslam map frame (origin: first left camera, z up)";

// The CRS and the offsets of a GeoTIFF (dem_files.hpp).
struct Georef {
  OGRSpatialReference srs;
  double x0_m = 0, y0_m = 0, alt_m = 0;
  std::vector<std::pair<std::string, std::string>> metadata;
};

std::string num(double v) { return CPLSPrintf("%.17g", v); }

Status makeGeoref(const std::string& path, const GeoOrigin* geo, Georef& g) {
  if (geo == nullptr) {
    g.srs.SetLocalCS(kLocalCs);
    g.srs.SetLinearUnits(SRS_UL_METER, 1.0);
    return Status::ok();
  }
  if (!(geo->lat_deg >= -80.0 && geo->lat_deg <= 84.0) ||
      !(geo->lon_deg >= -180.0 && geo->lon_deg <= 180.0) || !std::isfinite(geo->alt_m))
    return Status::invalidArgument("cannot write " + path + ": geographic origin (lat " +
                                   num(geo->lat_deg) + ", lon " + num(geo->lon_deg) + ", alt " +
                                   num(geo->alt_m) +
                                   ") is outside the UTM range (lat [-80, 84] deg, lon "
                                   "[-180, 180] deg, finite alt)");
  const int zone = std::min(60, static_cast<int>(std::floor((geo->lon_deg + 180.0) / 6.0)) + 1);
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // (lon, lat)
  g.srs.SetWellKnownGeogCS("WGS84");
  g.srs.SetUTM(zone, geo->lat_deg >= 0.0 ? TRUE : FALSE);
  g.srs.AutoIdentifyEPSG();                                  // EPSG:326zz / 327zz
  g.srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // (easting, northing)
  std::unique_ptr<OGRCoordinateTransformation> ct(
      OGRCreateCoordinateTransformation(&wgs84, &g.srs));
  double x = geo->lon_deg, y = geo->lat_deg;
  if (!ct || !ct->Transform(1, &x, &y) || !std::isfinite(x) || !std::isfinite(y))
    return Status::ioError("cannot write " + path + ": cannot project the origin to UTM zone " +
                           std::to_string(zone));
  g.x0_m = x;
  g.y0_m = y;
  g.alt_m = geo->alt_m;
  g.metadata = {{"SVSLAM_ORIGIN_EASTING_M", num(x)},
                {"SVSLAM_ORIGIN_NORTHING_M", num(y)},
                {"SVSLAM_ORIGIN_ALT_M", num(geo->alt_m)},
                {"SVSLAM_ORIGIN_LAT_DEG", num(geo->lat_deg)},
                {"SVSLAM_ORIGIN_LON_DEG", num(geo->lon_deg)}};
  return Status::ok();
}

struct Band {
  const char* description;
  const char* unit;  // "" for none
  GDALDataType type;
  const void* data;  // rows x cols values of `type`
};

// A temporary name beside `path`, unique per process and call.
std::string tempName(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

// Renames `tmp` over `path`; removes `tmp` when that fails.
Status commit(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (!ec) return Status::ok();
  std::error_code ignored;
  std::filesystem::remove(tmp, ignored);
  return Status::ioError("cannot write " + path + ": cannot rename " + tmp +
                         " to it: " + ec.message());
}

// A GeoTIFF of `bands` (all of one type) with the georeference of `g`, written atomically.
Status writeGeoTiff(const std::string& path, const map::DemRaster& r, const Georef& g,
                    const std::vector<Band>& bands, double nodata) {
  gdal::registerDrivers();
  gdal::ErrorCapture errors;
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (driver == nullptr)
    return Status::ioError("cannot write " + path + ": GDAL has no GTiff driver");
  const std::string tmp = tempName(path);
  CPLStringList options;
  options.SetNameValue("COMPRESS", "DEFLATE");
  options.SetNameValue("PREDICTOR", bands[0].type == GDT_Float32 ? "3" : "2");
  options.SetNameValue("BIGTIFF", "IF_SAFER");
  GDALDataset* ds = driver->Create(tmp.c_str(), r.cols, r.rows, static_cast<int>(bands.size()),
                                   bands[0].type, options.List());
  auto fail = [&](const std::string& what) {
    if (ds != nullptr) GDALClose(ds);
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    std::filesystem::remove(tmp + ".aux.xml", ignored);
    return Status::ioError("cannot write " + path + ": " + what + ": " + errors.message());
  };
  if (ds == nullptr) return fail("cannot create " + tmp);
  double gt[6] = {g.x0_m + r.i0 * r.cell_m,
                  r.cell_m,
                  0.0,
                  g.y0_m + (static_cast<double>(r.j0) + r.rows) * r.cell_m,
                  0.0,
                  -r.cell_m};
  if (ds->SetGeoTransform(gt) != CE_None) return fail("cannot set the geotransform");
  if (ds->SetSpatialRef(&g.srs) != CE_None) return fail("cannot set the CRS");
  for (const auto& [key, value] : g.metadata)
    if (ds->SetMetadataItem(key.c_str(), value.c_str()) != CE_None)
      return fail("cannot set metadata " + key);
  for (std::size_t b = 0; b < bands.size(); ++b) {
    GDALRasterBand* band = ds->GetRasterBand(static_cast<int>(b) + 1);
    band->SetDescription(bands[b].description);
    if (*bands[b].unit != '\0' && band->SetUnitType(bands[b].unit) != CE_None)
      return fail("cannot set the unit of band " + std::to_string(b + 1));
    if (band->SetNoDataValue(nodata) != CE_None)
      return fail("cannot set the nodata value of band " + std::to_string(b + 1));
    if (band->RasterIO(GF_Write, 0, 0, r.cols, r.rows, const_cast<void*>(bands[b].data), r.cols,
                       r.rows, bands[b].type, 0, 0, nullptr) != CE_None)
      return fail("cannot write band " + std::to_string(b + 1));
  }
  GDALClose(ds);  // flushes; void in GDAL 3.6, so failures are read from `errors`
  ds = nullptr;
  if (errors.failed()) return fail("writing " + tmp + " failed");
  std::error_code ignored;
  std::filesystem::remove(tmp + ".aux.xml", ignored);  // nothing should go there; never leak it
  return commit(tmp, path);
}

Status checkForWriting(const std::string& path, const map::DemRaster& r, bool need_luminance) {
  if (Status s = map::checkDemRaster(r, "cannot write " + path); !s) return s;
  if (r.cols == 0 || r.rows == 0)
    return Status::invalidArgument("cannot write " + path + ": the raster has no cells");
  if (need_luminance && r.luminance.size() != r.height_m.size())
    return Status::invalidArgument("cannot write " + path + ": luminance holds " +
                                   std::to_string(r.luminance.size()) + " values for " +
                                   std::to_string(r.height_m.size()) + " cells");
  return Status::ok();
}

Status writeGreyPng(const std::string& path, const map::DemRaster& r, const std::uint8_t* grey) {
  std::vector<unsigned char> png;
  try {
    const cv::Mat m(r.rows, r.cols, CV_8UC1, const_cast<std::uint8_t*>(grey));
    if (!cv::imencode(".png", m, png))
      return Status::ioError("cannot write " + path + ": PNG encoding failed");
  } catch (const cv::Exception& e) {
    return Status::ioError("cannot write " + path + ": PNG encoding failed: " + e.what());
  }
  return writeFileAtomically(path, png.data(), png.size());
}

}  // namespace

Status writeDemGeoTiff(const std::string& path, const map::DemRaster& dem, const GeoOrigin* geo) {
  if (Status s = checkForWriting(path, dem, false); !s) return s;
  Georef g;
  if (Status s = makeGeoref(path, geo, g); !s) return s;
  std::vector<float> height = dem.height_m;
  if (g.alt_m != 0.0)
    for (float& h : height) h = static_cast<float>(static_cast<double>(h) + g.alt_m);
  return writeGeoTiff(path, dem, g,
                      {{"height_m", "m", GDT_Float32, height.data()},
                       {"sigma_m", "m", GDT_Float32, dem.sigma_m.data()},
                       {"count", "", GDT_Float32, dem.count.data()}},
                      std::nan(""));
}

Status writeOrthoTiff(const std::string& path, const map::DemRaster& dem, const GeoOrigin* geo) {
  if (Status s = checkForWriting(path, dem, true); !s) return s;
  Georef g;
  if (Status s = makeGeoref(path, geo, g); !s) return s;
  return writeGeoTiff(path, dem, g, {{"luminance", "", GDT_Byte, dem.luminance.data()}}, 0.0);
}

Status writeOrthoPng(const std::string& path, const map::DemRaster& dem) {
  if (Status s = checkForWriting(path, dem, true); !s) return s;
  return writeGreyPng(path, dem, dem.luminance.data());
}

Status writeHillshadePng(const std::string& path, const map::DemRaster& dem) {
  if (Status s = checkForWriting(path, dem, false); !s) return s;
  auto shade = map::hillshade(dem);
  if (!shade)
    return Status::invalidArgument("cannot write " + path + ": " + shade.status().message());
  return writeGreyPng(path, dem, shade->data());
}

}  // namespace svslam::drivers

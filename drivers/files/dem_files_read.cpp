// readDemGeoTiff (dem_files.hpp).
#include <gdal_priv.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>

#include "drivers/files/dem_files.hpp"
#include "drivers/files/gdal_support.hpp"

namespace svslam::drivers {

namespace {

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(ds); }
};

// The SVSLAM_ORIGIN_* metadata item `key` (0 when absent); false when present but not a number.
bool originItem(GDALDataset& ds, const char* key, double& value) {
  value = 0.0;
  const char* text = ds.GetMetadataItem(key);
  if (text == nullptr) return true;
  char* end = nullptr;
  value = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(value);
}

}  // namespace

Result<map::DemRaster> readDemGeoTiff(const std::string& path) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(st)) return Status::notFound("DEM file does not exist: " + path);
  if (std::filesystem::is_directory(st))
    return Status::invalidArgument("DEM file is a directory, not a file: " + path);

  gdal::registerDrivers();
  gdal::ErrorCapture errors;
  const char* const drivers[] = {"GTiff", nullptr};
  std::unique_ptr<GDALDataset, DatasetCloser> ds(GDALDataset::Open(
      path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, drivers, nullptr, nullptr));
  if (!ds)
    return Status::corruptData("not a GeoTIFF: " + path + ": " +
                               errors.message("GDAL does not recognise it"));
  auto corrupt = [&](const std::string& why) { return Status::corruptData(path + ": " + why); };
  if (ds->GetRasterCount() != 3)
    return corrupt("band count " + std::to_string(ds->GetRasterCount()) +
                   "; a DEM has 3 bands (height_m, sigma_m, count)");
  double gt[6];
  if (ds->GetGeoTransform(gt) != CE_None) return corrupt("has no geotransform");
  for (double v : gt)
    if (!std::isfinite(v)) return corrupt("has a non-finite geotransform");
  if (gt[2] != 0.0 || gt[4] != 0.0 || !(gt[1] > 0.0) || !(gt[5] < 0.0))
    return corrupt("is not north-up (geotransform " + std::to_string(gt[1]) + ", " +
                   std::to_string(gt[2]) + ", " + std::to_string(gt[4]) + ", " +
                   std::to_string(gt[5]) + ")");
  if (std::abs(gt[1] + gt[5]) > 1e-9 * gt[1])
    return corrupt("cells are not square (" + std::to_string(gt[1]) + " x " +
                   std::to_string(-gt[5]) + " m)");
  const long long cells = static_cast<long long>(ds->GetRasterXSize()) * ds->GetRasterYSize();
  if (cells <= 0 || cells > (1LL << 28))
    return corrupt("has " + std::to_string(cells) + " cells (expected 1 to 2^28)");

  double east_m = 0, north_m = 0, alt_m = 0;
  if (!originItem(*ds, "SVSLAM_ORIGIN_EASTING_M", east_m) ||
      !originItem(*ds, "SVSLAM_ORIGIN_NORTHING_M", north_m) ||
      !originItem(*ds, "SVSLAM_ORIGIN_ALT_M", alt_m))
    return corrupt("has an SVSLAM_ORIGIN_* metadata item that is not a number");

  map::DemRaster r;
  r.cell_m = gt[1];
  const double i0 = std::round((gt[0] - east_m) / r.cell_m);
  const double top = std::round((gt[3] - north_m) / r.cell_m);
  const int rows = ds->GetRasterYSize();
  constexpr double kIntMax = std::numeric_limits<int>::max();
  if (!(std::abs(i0) < kIntMax / 2 && std::abs(top) < kIntMax / 2))
    return corrupt("its origin is too far from the map origin for int cell indices");
  r.i0 = static_cast<int>(i0);
  r.j0 = static_cast<int>(top) - rows;
  r.resize(ds->GetRasterXSize(), rows);
  std::vector<float>* dst[3] = {&r.height_m, &r.sigma_m, &r.count};
  for (int b = 0; b < 3; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b + 1);
    if (band->RasterIO(GF_Read, 0, 0, r.cols, r.rows, dst[b]->data(), r.cols, r.rows, GDT_Float32,
                       0, 0, nullptr) != CE_None ||
        errors.failed())
      return corrupt("cannot read band " + std::to_string(b + 1) + ": " + errors.message());
    // A foreign nodata value (e.g. -9999) becomes the raster's own: NaN, or 0 for the count.
    int has_nodata = 0;
    const double nodata = band->GetNoDataValue(&has_nodata);
    if (has_nodata && !std::isnan(nodata))
      for (float& v : *dst[b])
        if (static_cast<double>(v) == static_cast<double>(static_cast<float>(nodata)))
          v = b == 2 ? 0.0f : NAN;
  }
  if (alt_m != 0.0)
    for (float& h : r.height_m) h = static_cast<float>(static_cast<double>(h) - alt_m);
  return r;
}

}  // namespace svslam::drivers

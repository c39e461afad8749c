// The elevation map's files: GeoTIFF round trip, georeference (local CRS, UTM), PNGs.
#include "drivers/files/dem_files.hpp"

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "../../core/test_files.hpp"
#include "dem_test_support.hpp"
#include "map/hillshade.hpp"

namespace svslam::drivers {
namespace {

namespace fs = std::filesystem;

struct Closer {
  void operator()(GDALDataset* ds) const { GDALClose(ds); }
};
using Dataset = std::unique_ptr<GDALDataset, Closer>;

Dataset openWithGdal(const fs::path& p) {
  GDALAllRegister();
  return Dataset(GDALDataset::Open(p.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
}

class DemFiles : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::freshTestDir("svslam_dem_files_"); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(DemFiles, RoundTripIsExact) {
  for (const auto& [i0, j0] : {std::pair{-7, -3}, std::pair{12, 40}, std::pair{0, 0}}) {
    const map::DemRaster dem = test::sampleDem(5, 4, i0, j0, 0.2);
    const std::string path = (dir_ / "dem.tif").string();
    ASSERT_TRUE(writeDemGeoTiff(path, dem).isOk());
    auto back = readDemGeoTiff(path);
    ASSERT_TRUE(back.isOk()) << back.status().message();
    EXPECT_EQ(back->cell_m, dem.cell_m);
    EXPECT_EQ(back->i0, i0);
    EXPECT_EQ(back->j0, j0);
    EXPECT_EQ(back->cols, 5);
    EXPECT_EQ(back->rows, 4);
    EXPECT_TRUE(test::sameBits(back->height_m, dem.height_m));
    EXPECT_TRUE(test::sameBits(back->sigma_m, dem.sigma_m));
    EXPECT_TRUE(test::sameBits(back->count, dem.count));
    EXPECT_TRUE(std::isnan(back->height_m[3]));
  }
}

TEST_F(DemFiles, DemGeoTiffLayoutWithoutGeoOrigin) {
  const map::DemRaster dem = test::sampleDem(6, 3, -4, -9, 0.5);
  const fs::path path = dir_ / "dem.tif";
  ASSERT_TRUE(writeDemGeoTiff(path.string(), dem).isOk());
  Dataset ds = openWithGdal(path);
  ASSERT_TRUE(ds);
  EXPECT_STREQ(ds->GetDriver()->GetDescription(), "GTiff");
  ASSERT_EQ(ds->GetRasterCount(), 3);
  double gt[6];
  ASSERT_EQ(ds->GetGeoTransform(gt), CE_None);
  EXPECT_DOUBLE_EQ(gt[0], -4 * 0.5);
  EXPECT_DOUBLE_EQ(gt[1], 0.5);
  EXPECT_DOUBLE_EQ(gt[2], 0.0);
  EXPECT_DOUBLE_EQ(gt[3], (-9 + 3) * 0.5);
  EXPECT_DOUBLE_EQ(gt[4], 0.0);
  EXPECT_DOUBLE_EQ(gt[5], -0.5);
  const char* names[] = {"height_m", "sigma_m", "count"};
  for (int b = 1; b <= 3; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b);
    EXPECT_EQ(band->GetRasterDataType(), GDT_Float32);
    EXPECT_STREQ(band->GetDescription(), names[b - 1]);
    int has = 0;
    EXPECT_TRUE(std::isnan(band->GetNoDataValue(&has)));
    EXPECT_TRUE(has);
  }
  EXPECT_STREQ(ds->GetRasterBand(1)->GetUnitType(), "m");
  const OGRSpatialReference* srs = ds->GetSpatialRef();
  ASSERT_NE(srs, nullptr);
  EXPECT_TRUE(srs->IsLocal());
  EXPECT_NE(std::string(srs->GetName()).find("svslam map frame"), std::string::npos)
      << srs->GetName();
  EXPECT_DOUBLE_EQ(srs->GetLinearUnits(), 1.0);
  EXPECT_FALSE(fs::exists(path.string() + ".aux.xml"));
}

void expectUtm(const fs::path& path, const char* epsg, double e_min, double e_max, double n_min,
               double n_max) {
  Dataset ds = openWithGdal(path);
  ASSERT_TRUE(ds);
  const OGRSpatialReference* srs = ds->GetSpatialRef();
  ASSERT_NE(srs, nullptr);
  EXPECT_TRUE(srs->IsProjected());
  ASSERT_NE(srs->GetAuthorityCode(nullptr), nullptr);
  EXPECT_STREQ(srs->GetAuthorityName(nullptr), "EPSG");
  EXPECT_STREQ(srs->GetAuthorityCode(nullptr), epsg);
  double gt[6];
  ASSERT_EQ(ds->GetGeoTransform(gt), CE_None);
  EXPECT_GT(gt[0], e_min);
  EXPECT_LT(gt[0], e_max);
  EXPECT_GT(gt[3], n_min);
  EXPECT_LT(gt[3], n_max);
}

TEST_F(DemFiles, GeoOriginGivesUtmAndShiftedGeotransform) {
  const map::DemRaster dem = test::sampleDem(4, 4, -10, 20, 0.25);
  const GeoOrigin munich{48.137, 11.575, 520.0};  // UTM 32N; 11.575 E is 2.6 deg east of 9 E
  const fs::path path = dir_ / "dem.tif";
  ASSERT_TRUE(writeDemGeoTiff(path.string(), dem, &munich).isOk());
  // Easting of 11.575 E at 48.1 N: ~ 500 km + 2.575 deg * 74.4 km/deg = ~691 km.
  expectUtm(path, "32632", 685000, 697000, 5.33e6, 5.34e6);
  Dataset ds = openWithGdal(path);
  double gt[6];
  ASSERT_EQ(ds->GetGeoTransform(gt), CE_None);
  const double e0 = std::stod(ds->GetMetadataItem("SVSLAM_ORIGIN_EASTING_M"));
  const double n0 = std::stod(ds->GetMetadataItem("SVSLAM_ORIGIN_NORTHING_M"));
  EXPECT_DOUBLE_EQ(gt[0], e0 - 10 * 0.25);
  EXPECT_DOUBLE_EQ(gt[3], n0 + (20 + 4) * 0.25);
  float h = 0;
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, 1, 1, &h, 1, 1, GDT_Float32, 0, 0),
            CE_None);
  EXPECT_NEAR(h, dem.height_m[0] + 520.0, 1e-4);

  // Read back in the map frame: indices exact, heights within float rounding of alt + h.
  auto back = readDemGeoTiff(path.string());
  ASSERT_TRUE(back.isOk()) << back.status().message();
  EXPECT_EQ(back->i0, -10);
  EXPECT_EQ(back->j0, 20);
  for (std::size_t k = 0; k < dem.height_m.size(); ++k) {
    if (std::isnan(dem.height_m[k])) {
      EXPECT_TRUE(std::isnan(back->height_m[k]));
    } else {
      EXPECT_NEAR(back->height_m[k], dem.height_m[k], 1e-4);
    }
  }
  EXPECT_TRUE(test::sameBits(back->sigma_m, dem.sigma_m));
}

TEST_F(DemFiles, SouthernAndWesternOriginsPickTheirZone) {
  const map::DemRaster dem = test::sampleDem(2, 2, 0, 0);
  const GeoOrigin cape_town{-33.92, 18.42, 10.0};  // zone 34 S
  ASSERT_TRUE(writeDemGeoTiff((dir_ / "s.tif").string(), dem, &cape_town).isOk());
  expectUtm(dir_ / "s.tif", "32734", 166000, 834000, 6.0e6, 6.5e6);
  const GeoOrigin quito{-0.18, -78.47, 2850.0};  // zone 17 S, just south of the equator
  ASSERT_TRUE(writeOrthoTiff((dir_ / "o.tif").string(), dem, &quito).isOk());
  expectUtm(dir_ / "o.tif", "32717", 166000, 834000, 9.9e6, 1.0e7);
}

TEST_F(DemFiles, OrthoTiffIsOneByteBand) {
  const map::DemRaster dem = test::sampleDem(7, 5, 3, -2, 0.1);
  const fs::path path = dir_ / "ortho.tif";
  ASSERT_TRUE(writeOrthoTiff(path.string(), dem).isOk());
  Dataset ds = openWithGdal(path);
  ASSERT_TRUE(ds);
  ASSERT_EQ(ds->GetRasterCount(), 1);
  GDALRasterBand* band = ds->GetRasterBand(1);
  EXPECT_EQ(band->GetRasterDataType(), GDT_Byte);
  int has = 0;
  EXPECT_EQ(band->GetNoDataValue(&has), 0.0);
  EXPECT_TRUE(has);
  double gt[6];
  ASSERT_EQ(ds->GetGeoTransform(gt), CE_None);
  EXPECT_DOUBLE_EQ(gt[0], 0.3);
  EXPECT_DOUBLE_EQ(gt[3], 0.3);
  std::vector<std::uint8_t> grey(dem.luminance.size());
  ASSERT_EQ(band->RasterIO(GF_Read, 0, 0, 7, 5, grey.data(), 7, 5, GDT_Byte, 0, 0), CE_None);
  EXPECT_EQ(grey, dem.luminance);
  EXPECT_TRUE(ds->GetSpatialRef() != nullptr && ds->GetSpatialRef()->IsLocal());
}

TEST_F(DemFiles, PngsHoldTheOrthoimageAndTheHillshade) {
  map::DemRaster dem = test::sampleDem(9, 6, 0, 0);
  const std::string ortho = (dir_ / "ortho.png").string();
  const std::string shade = (dir_ / "dem_hillshade.png").string();
  ASSERT_TRUE(writeOrthoPng(ortho, dem).isOk());
  ASSERT_TRUE(writeHillshadePng(shade, dem).isOk());
  const cv::Mat o = cv::imread(ortho, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(o.type(), CV_8UC1);
  ASSERT_EQ(o.cols, 9);
  ASSERT_EQ(o.rows, 6);
  EXPECT_EQ(std::vector<std::uint8_t>(o.datastart, o.dataend), dem.luminance);
  const cv::Mat s = cv::imread(shade, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(s.type(), CV_8UC1);
  auto expected = map::hillshade(dem);
  ASSERT_TRUE(expected.isOk());
  EXPECT_EQ(std::vector<std::uint8_t>(s.datastart, s.dataend), *expected);
}

}  // namespace
}  // namespace svslam::drivers

// The elevation map's files on bad input and failing file systems: clear errors naming the file,
// atomic writes (a previous file stays byte for byte, no temporary is left), nothing on stderr.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "../../core/test_files.hpp"
#include "dem_test_support.hpp"
#include "drivers/files/dem_files.hpp"

namespace svslam::drivers {
namespace {

namespace fs = std::filesystem;
using test::slurp;

class DemFilesErrors : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::freshTestDir("svslam_dem_errors_"); }
  void TearDown() override {
    fs::permissions(dir_, fs::perms::owner_all);
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // No temporary left anywhere in the test folder.
  void expectNoTemporaries() const {
    for (const auto& e : fs::recursive_directory_iterator(dir_))
      EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  }
  fs::path dir_;
};

using Writer = std::function<Status(const std::string&, const map::DemRaster&)>;
const std::vector<std::pair<const char*, Writer>>& writers() {
  static const std::vector<std::pair<const char*, Writer>> w = {
      {"dem.tif",
       [](const std::string& p, const map::DemRaster& r) { return writeDemGeoTiff(p, r); }},
      {"ortho.tif",
       [](const std::string& p, const map::DemRaster& r) { return writeOrthoTiff(p, r); }},
      {"ortho.png", writeOrthoPng},
      {"dem_hillshade.png", writeHillshadePng}};
  return w;
}

void expectErrorNaming(const Status& s, const std::string& path) {
  EXPECT_FALSE(s.isOk()) << path;
  EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
}

TEST_F(DemFilesErrors, MissingDirectoryIsAnErrorNamingThePath) {
  const map::DemRaster dem = test::sampleDem(4, 3, 0, 0);
  for (const auto& [name, write] : writers()) {
    const std::string p = path(std::string("no_such_dir/") + name);
    ::testing::internal::CaptureStderr();
    const Status s = write(p, dem);
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "") << name;  // GDAL kept quiet
    expectErrorNaming(s, p);
    EXPECT_EQ(s.code(), StatusCode::kIoError);
  }
  EXPECT_FALSE(fs::exists(dir_ / "no_such_dir"));
}

TEST_F(DemFilesErrors, TargetThatIsADirectoryIsKept) {
  const map::DemRaster dem = test::sampleDem(4, 3, 0, 0);
  for (const auto& [name, write] : writers()) {
    fs::create_directory(dir_ / name);
    std::ofstream(dir_ / name / "keep.txt") << "precious";
    const Status s = write(path(name), dem);
    expectErrorNaming(s, path(name));
    EXPECT_TRUE(fs::is_directory(dir_ / name));
    EXPECT_EQ(slurp(dir_ / name / "keep.txt"), "precious");
  }
  expectNoTemporaries();
}

// The temporary's name exceeds NAME_MAX (255) while the target's (253 bytes) does not: the write
// fails before touching the target, whatever the process's privileges.
TEST_F(DemFilesErrors, FailureLeavesThePreviousFileByteIdentical) {
  const map::DemRaster old_dem = test::sampleDem(4, 3, 0, 0);
  const map::DemRaster new_dem = test::sampleDem(6, 6, 1, 1);
  for (const auto& [name, write] : writers()) {
    ASSERT_TRUE(write(path(name), old_dem).isOk()) << name;
    const std::string old_bytes = slurp(path(name));
    ASSERT_FALSE(old_bytes.empty());
    const std::string long_name = std::string(253 - std::string(name).size(), 'x') + name;
    fs::copy_file(path(name), dir_ / long_name);
    const Status s = write(path(long_name), new_dem);
    expectErrorNaming(s, path(long_name));
    EXPECT_EQ(slurp(path(long_name)), old_bytes) << name;
  }
  expectNoTemporaries();
}

// A write that fails half-way (RLIMIT_FSIZE: the file system refuses to grow the file, as
// when the disk is full) keeps the previous file.
TEST_F(DemFilesErrors, WriteFailingHalfWayKeepsThePreviousFile) {
  map::DemRaster big = test::sampleDem(300, 300, 0, 0);
  std::uint32_t state = 12345;
  for (std::size_t k = 0; k < big.height_m.size(); ++k) {  // incompressible noise
    state = state * 1664525u + 1013904223u;
    big.height_m[k] = static_cast<float>(state >> 8) * 1e-6f;
    big.luminance[k] = static_cast<std::uint8_t>(1 + (state >> 24) % 255);
  }
  for (const auto& [name, write] : writers()) {
    ASSERT_TRUE(write(path(name), test::sampleDem(4, 3, 0, 0)).isOk()) << name;
    const std::string old_bytes = slurp(path(name));
    rlimit old_limit{};
    ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
    auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
    rlimit small = old_limit;
    small.rlim_cur = 16384;
    ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
    const Status s = write(path(name), big);
    setrlimit(RLIMIT_FSIZE, &old_limit);
    std::signal(SIGXFSZ, old_handler);
    expectErrorNaming(s, path(name));
    EXPECT_EQ(slurp(path(name)), old_bytes) << name;
  }
  expectNoTemporaries();
}

TEST_F(DemFilesErrors, ReadOnlyDirectoryKeepsThePreviousFile) {
  if (::geteuid() == 0) GTEST_SKIP() << "running as root: permissions are not enforced";
  const map::DemRaster dem = test::sampleDem(4, 3, 0, 0);
  for (const auto& [name, write] : writers()) {
    ASSERT_TRUE(write(path(name), dem).isOk()) << name;
  }
  fs::permissions(dir_, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                            fs::perms::group_exec | fs::perms::others_read |
                            fs::perms::others_exec);
  for (const auto& [name, write] : writers()) {
    const std::string old_bytes = slurp(path(name));
    expectErrorNaming(write(path(name), test::sampleDem(5, 5, 2, 2)), path(name));
    EXPECT_EQ(slurp(path(name)), old_bytes) << name;
  }
}

TEST_F(DemFilesErrors, BadRastersAndOriginsAreRefused) {
  map::DemRaster empty;
  for (const auto& [name, write] : writers())
    expectErrorNaming(write(path(name), empty), path(name));
  map::DemRaster bad = test::sampleDem(3, 3, 0, 0);
  bad.luminance.resize(2);
  expectErrorNaming(writeOrthoTiff(path("o.tif"), bad), path("o.tif"));
  expectErrorNaming(writeOrthoPng(path("o.png"), bad), path("o.png"));
  bad = test::sampleDem(3, 3, 0, 0);
  bad.count.pop_back();
  expectErrorNaming(writeDemGeoTiff(path("d.tif"), bad), path("d.tif"));
  const map::DemRaster good = test::sampleDem(3, 3, 0, 0);
  for (const GeoOrigin& g : {GeoOrigin{89.0, 0, 0}, GeoOrigin{0, 181.0, 0}, GeoOrigin{NAN, 0, 0},
                             GeoOrigin{10, 10, INFINITY}}) {
    const Status s = writeDemGeoTiff(path("g.tif"), good, &g);
    expectErrorNaming(s, path("g.tif"));
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  }
  EXPECT_FALSE(fs::exists(path("g.tif")));
  expectNoTemporaries();
}

TEST_F(DemFilesErrors, ReadingBadFilesGivesClearErrors) {
  auto expectRead = [](const std::string& p, StatusCode code, const std::string& needle) {
    ::testing::internal::CaptureStderr();
    auto r = readDemGeoTiff(p);
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "") << p;
    ASSERT_FALSE(r.isOk()) << p;
    EXPECT_EQ(r.status().code(), code) << r.status().message();
    EXPECT_NE(r.status().message().find(p), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find(needle), std::string::npos) << r.status().message();
  };
  expectRead(path("missing.tif"), StatusCode::kNotFound, "does not exist");
  expectRead(dir_.string(), StatusCode::kInvalidArgument, "directory");
  std::ofstream(path("text.tif")) << "not a tiff at all\n";
  expectRead(path("text.tif"), StatusCode::kCorruptData, "not a GeoTIFF");
  const map::DemRaster dem = test::sampleDem(40, 30, 0, 0);
  ASSERT_TRUE(writeOrthoPng(path("ortho.png"), dem).isOk());
  expectRead(path("ortho.png"), StatusCode::kCorruptData, "not a GeoTIFF");
  ASSERT_TRUE(writeOrthoTiff(path("ortho.tif"), dem).isOk());
  expectRead(path("ortho.tif"), StatusCode::kCorruptData, "band count 1");
  // Truncated: an error, never a crash.
  ASSERT_TRUE(writeDemGeoTiff(path("dem.tif"), dem).isOk());
  const std::string bytes = slurp(path("dem.tif"));
  std::ofstream(path("cut.tif"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  EXPECT_FALSE(readDemGeoTiff(path("cut.tif")).isOk());
  std::ofstream(path("empty.tif"), std::ios::binary).flush();
  EXPECT_FALSE(readDemGeoTiff(path("empty.tif")).isOk());
}

// A 3-band GeoTIFF written with GDAL directly, with the geotransform `gt`.
void writeRawTiff(const std::string& p, const double gt[6]) {
  GDALAllRegister();
  GDALDataset* ds = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(p.c_str(), 2, 2, 3,
                                                                             GDT_Float32, nullptr);
  ASSERT_NE(ds, nullptr);
  ds->SetGeoTransform(const_cast<double*>(gt));
  GDALClose(ds);
}

TEST_F(DemFilesErrors, RotatedSouthUpOrNonSquareGeotransformsAreRefused) {
  const double rotated[6] = {0, 0.1, 0.01, 0, 0, -0.1};
  const double south_up[6] = {0, 0.1, 0, 0, 0, 0.1};
  const double non_square[6] = {0, 0.1, 0, 0, 0, -0.2};
  const double ok[6] = {-0.3, 0.1, 0, 0.5, 0, -0.1};
  writeRawTiff(path("rotated.tif"), rotated);
  writeRawTiff(path("south_up.tif"), south_up);
  writeRawTiff(path("non_square.tif"), non_square);
  writeRawTiff(path("ok.tif"), ok);
  for (const char* bad : {"rotated.tif", "south_up.tif"}) {
    auto r = readDemGeoTiff(path(bad));
    ASSERT_FALSE(r.isOk());
    EXPECT_NE(r.status().message().find("north-up"), std::string::npos) << r.status().message();
  }
  auto r = readDemGeoTiff(path("non_square.tif"));
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.status().message().find("square"), std::string::npos) << r.status().message();
  auto good = readDemGeoTiff(path("ok.tif"));
  ASSERT_TRUE(good.isOk()) << good.status().message();
  EXPECT_EQ(good->i0, -3);
  EXPECT_EQ(good->j0, 3);  // top edge y = 0.5 m: 5 cells, minus 2 rows
}

}  // namespace
}  // namespace svslam::drivers

#include "drivers/datasets/stereo_datasets.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "../../core/test_files.hpp"
#include "drivers/files/image_io.hpp"

namespace svslam::drivers {
namespace {

namespace fs = std::filesystem;

std::string dataDir(const std::string& sub) { return std::string(SVSLAM_DATA_DIR) + "/" + sub; }

#define SKIP_WITHOUT(dir)                                                      \
  do {                                                                         \
    if (!fs::is_directory(dir)) GTEST_SKIP() << "no stereo data at " << (dir); \
  } while (0)

// A case was found and each of its fields is the one in `want`.
void expectCase(const Result<StereoGtCase>& r, const StereoGtCase& want) {
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->name, want.name);
  EXPECT_EQ(r->left, want.left);
  EXPECT_EQ(r->right, want.right);
  EXPECT_EQ(r->gt, want.gt);
  EXPECT_EQ(r->mask, want.mask);
  EXPECT_EQ(r->gt_scale, want.gt_scale);
  EXPECT_EQ(r->max_disp, want.max_disp);
}

struct V2Expect {
  const char* name;
  double scale;
  int max_disp;
};

TEST(StereoDatasets, MiddleburyV2AllFour) {
  for (const V2Expect& e : {V2Expect{"tsukuba", 16, 15}, V2Expect{"venus", 8, 19},
                            V2Expect{"teddy", 4, 59}, V2Expect{"cones", 4, 59}}) {
    const std::string dir = dataDir(std::string("middlebury_v2/") + e.name);
    SKIP_WITHOUT(dir);
    ASSERT_NO_FATAL_FAILURE(
        expectCase(findStereoGtCase(dir),
                   {e.name, dir + "/imL.png", dir + "/imR.png", dir + "/groundtruth.png",
                    dir + "/nonocc.png", e.scale, e.max_disp}));
    for (const char* kind : {"all", "disc"}) {
      const Result<StereoGtCase> k = findStereoGtCase(dir + "/", kind);
      ASSERT_TRUE(k.isOk()) << k.status().message();
      EXPECT_EQ(k->name, e.name);  // trailing slash does not matter
      EXPECT_EQ(fs::path(k->mask).filename().string(), std::string(kind) + ".png");
    }
  }
}

TEST(StereoDatasets, MiddleburyV2FilesLoad) {
  const std::string dir = dataDir("middlebury_v2/tsukuba");
  SKIP_WITHOUT(dir);
  const Result<StereoGtCase> c = findStereoGtCase(dir, "nonocc");
  ASSERT_TRUE(c.isOk());
  const Result<ImageU8> left = loadGrey(c->left);
  const Result<ImageF32> gt = loadDisparity(c->gt, c->gt_scale);
  const Result<ImageU8> mask = loadMask(c->mask);
  ASSERT_TRUE(left.isOk() && gt.isOk() && mask.isOk());
  EXPECT_EQ(left->width(), gt->width());
  EXPECT_EQ(left->height(), mask->height());
}

TEST(StereoDatasets, Middlebury2006Aloe) {
  const std::string dir = dataDir("middlebury2006_aloe");
  SKIP_WITHOUT(dir);
  // max_disp: GT max 211 -> 212 -> next multiple of 16.
  ASSERT_NO_FATAL_FAILURE(
      expectCase(findStereoGtCase(dir), {"middlebury2006_aloe", dir + "/aloeL.jpg",
                                         dir + "/aloeR.jpg", dir + "/aloeGT.png", "", 1.0, 224}));
  EXPECT_TRUE(findStereoGtCase(dir, "nonocc", "aloe").isOk());
  EXPECT_EQ(findStereoGtCase(dir, "nonocc", "cactus").status().code(), StatusCode::kNotFound);
}

TEST(StereoDatasets, KittiStereo2012) {
  const std::string dir = dataDir("kitti_stereo2012_000070");
  SKIP_WITHOUT(dir);
  const Result<StereoGtCase> r = findStereoGtCase(dir);
  // max_disp 256 < width 1241.
  ASSERT_NO_FATAL_FAILURE(expectCase(
      r, {"kitti_stereo2012_000070_000070_10", dir + "/image_0/000070_10.png",
          dir + "/image_1/000070_10.png", dir + "/disp_noc/000070_10.png", "", 256.0, 256}));

  const Result<StereoGtCase> all = findStereoGtCase(dir, "all", "000070");
  ASSERT_TRUE(all.isOk()) << all.status().message();
  EXPECT_EQ(all->gt, dir + "/disp_occ/000070_10.png");
  EXPECT_TRUE(findStereoGtCase(dir, "nonocc", "000070_10.png").isOk());
  EXPECT_TRUE(findStereoGtCase(dir, "nonocc", "000070_10").isOk());
  EXPECT_EQ(findStereoGtCase(dir, "disc").status().code(), StatusCode::kInvalidArgument);
  const Result<StereoGtCase> missing = findStereoGtCase(dir, "nonocc", "000071");
  ASSERT_FALSE(missing.isOk());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_NE(missing.status().message().find("000071_10.png"), std::string::npos);

  const Result<ImageF32> gt = loadDisparity(r->gt, r->gt_scale);
  ASSERT_TRUE(gt.isOk()) << gt.status().message();
  EXPECT_EQ(gt->width(), 1241);
  EXPECT_EQ(gt->height(), 376);
}

// Synthetic folders in a temp dir: always runs, no shared data needed.
class StereoDatasetsTmp : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = svslam::test::freshTestDir("svslam_stereo_datasets_test_"); }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  void touch(const std::string& rel, const std::string& content = "x") const {
    fs::create_directories((dir_ / rel).parent_path());
    std::ofstream(dir_ / rel) << content;
  }
  fs::path dir_;
};

TEST_F(StereoDatasetsTmp, UnknownLayoutListsWhatWasExpected) {
  touch("left.png");
  touch("right.png");
  const Result<StereoGtCase> r = findStereoGtCase(dir_.string());
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  const std::string& m = r.status().message();
  EXPECT_NE(m.find(dir_.string()), std::string::npos) << m;
  for (const char* expected :
       {"imL.png", "groundtruth.png", "info.txt", "GT.png", "image_0", "disp_noc"}) {
    EXPECT_NE(m.find(expected), std::string::npos) << expected << " missing in: " << m;
  }
}

TEST_F(StereoDatasetsTmp, MissingFolderAndBadMaskKind) {
  EXPECT_EQ(findStereoGtCase((dir_ / "nope").string()).status().code(), StatusCode::kNotFound);
  EXPECT_EQ(findStereoGtCase(dir_.string(), "occ").status().code(), StatusCode::kInvalidArgument);
  touch("a_file");
  EXPECT_EQ(findStereoGtCase((dir_ / "a_file").string()).status().code(),
            StatusCode::kInvalidArgument);
}

TEST_F(StereoDatasetsTmp, MiddleburyV2BadInfoOrMissingMask) {
  for (const char* f : {"imL.png", "imR.png", "groundtruth.png", "nonocc.png"}) touch(f);
  touch("info.txt", "abc\n60\n");
  Result<StereoGtCase> r = findStereoGtCase(dir_.string());
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData) << r.status().message();
  touch("info.txt", "4\n");
  r = findStereoGtCase(dir_.string());
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData) << r.status().message();
  touch("info.txt", "4\n60\n");
  r = findStereoGtCase(dir_.string());
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(r->gt_scale, 4.0);
  EXPECT_EQ(r->max_disp, 60);
  r = findStereoGtCase(dir_.string(), "disc");
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  EXPECT_NE(r.status().message().find("disc.png"), std::string::npos) << r.status().message();
}

TEST_F(StereoDatasetsTmp, KittiWithoutGroundTruthForTheFrame) {
  touch("image_0/000001_10.png");
  touch("image_1/000001_10.png");
  fs::create_directories(dir_ / "disp_noc");
  const Result<StereoGtCase> r = findStereoGtCase(dir_.string());
  ASSERT_FALSE(r.isOk());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound) << r.status().message();
  // "all" asks for disp_occ/, which does not exist.
  EXPECT_EQ(findStereoGtCase(dir_.string(), "all").status().code(), StatusCode::kNotFound);
}

}  // namespace
}  // namespace svslam::drivers

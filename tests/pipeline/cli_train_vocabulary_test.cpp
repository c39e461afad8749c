// svslam train-vocabulary end to end: a folder and a list of small textured images give a
// vocabulary file that loads back; missing folders, empty folders, undecodable images and bad
// options give a clear error and a non-zero exit.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "cli_helpers.hpp"
#include "drivers/files/vocabulary_file.hpp"

namespace fs = std::filesystem;
using svslam::test::slurp;

namespace {

class CliTrainVocabulary : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = svslam::test::freshTestDir("svslam_cli_voc_");
    fs::create_directories(dir_ / "images");
    cv::RNG rng(5);
    for (int i = 0; i < 4; ++i) {  // blurred noise: plenty of FAST corners
      cv::Mat img(160, 200, CV_8UC1);
      rng.fill(img, cv::RNG::UNIFORM, 0, 256);
      cv::GaussianBlur(img, img, cv::Size(5, 5), 1.2);
      ASSERT_TRUE(
          cv::imwrite((dir_ / "images" / ("im" + std::to_string(i) + ".png")).string(), img));
    }
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  int run(const std::string& args, std::string& out, std::string& err) const {
    const int code = svslam::test::runSvslam(args, dir_ / "out.txt", dir_ / "err.txt");
    out = slurp(dir_ / "out.txt");
    err = slurp(dir_ / "err.txt");
    return code;
  }
  void expectError(const std::string& args, const std::string& needle) const {
    std::string out, err;
    const int code = run(args, out, err);
    EXPECT_TRUE(code == 1 || code == 2) << args << " exited " << code << "\n" << err;
    EXPECT_NE(err.find(needle), std::string::npos) << args << "\nstderr: " << err;
    EXPECT_TRUE(out.empty()) << out;
  }
  fs::path dir_;
};

TEST_F(CliTrainVocabulary, FolderAndListGiveALoadableVocabulary) {
  std::string out, err;
  ASSERT_EQ(run("train-vocabulary --images " + path("images") + " --out " + path("v.svvoc") +
                    " --branching 4 --depth 2 --seed 3",
                out, err),
            0)
      << err;
  EXPECT_NE(out.find("\"images\": 4"), std::string::npos) << out;
  for (const char* key : {"\"descriptors\"", "\"words\"", "\"bytes\"", "\"train_s\""})
    EXPECT_NE(out.find(key), std::string::npos) << out;
  auto voc = svslam::drivers::loadVocabulary(path("v.svvoc"));
  ASSERT_TRUE(voc.isOk()) << voc.status().message();
  EXPECT_EQ(voc->branching(), 4);
  EXPECT_GT(voc->numWords(), 4);

  std::ofstream(path("list.txt")) << "# two of them\nimages/im1.png\n\n"
                                  << path("images/im3.png") << "\n";
  ASSERT_EQ(run("train-vocabulary --images " + path("list.txt") + " --out " + path("w.svvoc") +
                    " --branching 4 --depth 2",
                out, err),
            0)
      << err;
  EXPECT_NE(out.find("\"images\": 2"), std::string::npos) << out;
  ASSERT_EQ(run("train-vocabulary --images " + path("images") + " --out " + path("x.svvoc") +
                    " --branching 4 --depth 2 --max-images 3",
                out, err),
            0)
      << err;
  EXPECT_NE(out.find("\"images\": 3"), std::string::npos) << out;
}

TEST_F(CliTrainVocabulary, BadInputIsAClearError) {
  expectError("train-vocabulary --images " + path("nowhere") + " --out " + path("v.svvoc"),
              path("nowhere"));
  fs::create_directories(dir_ / "empty");
  expectError("train-vocabulary --images " + path("empty") + " --out " + path("v.svvoc"),
              "no image");
  std::ofstream(path("images/broken.png")) << "not a png";
  expectError("train-vocabulary --images " + path("images") + " --out " + path("v.svvoc"),
              "broken.png");
  fs::remove(path("images/broken.png"));
  expectError("train-vocabulary --images " + path("images"), "--out");
  expectError("train-vocabulary --images " + path("images") + " --out " + path("v.svvoc") +
                  " --branching 1",
              "--branching");
  EXPECT_FALSE(fs::exists(path("v.svvoc")));
}

}  // namespace

// svslam calibrate through the executable: OpenCV's sample pairs (figures in the JSON, the file
// read back by the v4l2: reader), rendered pairs in two folders, and bad inputs (non-zero exit,
// a message naming the problem, nothing written).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "../drivers/calib/chessboard_scene.hpp"
#include "cli_helpers.hpp"
#include "drivers/camera/v4l2_source.hpp"
#include "drivers/files/stereo_calibration_file.hpp"

namespace fs = std::filesystem;

namespace svslam::test {
namespace {

// The number after "key": in a flat JSON text (NaN when absent).
double jsonNumber(const std::string& json, const std::string& key) {
  const std::size_t p = json.find("\"" + key + "\": ");
  if (p == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + p + key.size() + 4, nullptr);
}

// Writes rendered pairs 0..n-1 as <dir>/left0i.png + right0i.png, or into dir/L and dir/R.
void writeScene(const fs::path& dir, int n, bool two_folders) {
  const ChessboardScene s;
  if (two_folders) {
    fs::create_directories(dir / "L");
    fs::create_directories(dir / "R");
  }
  for (int i = 0; i < n; ++i) {
    cv::Mat l, r;
    ASSERT_TRUE(s.render(i, 0, l) && s.render(i, 1, r));
    std::string id = std::to_string(i);
    id.insert(id.begin(), '0');
    id += ".png";
    ASSERT_TRUE(
        cv::imwrite((two_folders ? dir / "L" / ("v" + id) : dir / ("left" + id)).string(), l));
    ASSERT_TRUE(
        cv::imwrite((two_folders ? dir / "R" / ("v" + id) : dir / ("right" + id)).string(), r));
  }
}

TEST(CliCalibrate, SamplePairsMeetTheBoundsAndTheFileReadsBack) {
  const std::string data = std::string(SVSLAM_DATA_DIR) + "/chessboard_calib";
  if (!fs::exists(data)) GTEST_SKIP() << "no calibration data at " << data;
  const fs::path dir = freshTestDir("svslam_cli_calib_");
  const int code = runSvslam(
      "calibrate --images " + data + " --board 9x6 --square 0.025 --out " + (dir / "out").string(),
      dir / "out.json", dir / "err.txt");
  ASSERT_EQ(code, 0) << slurp(dir / "err.txt");
  const std::string json = slurp(dir / "out.json");
  EXPECT_LE(jsonNumber(json, "rms_pair_px"), 0.5) << json;
  EXPECT_LE(jsonNumber(json, "rms_left_px"), 0.5) << json;
  EXPECT_LE(jsonNumber(json, "rms_right_px"), 0.5) << json;
  EXPECT_LE(jsonNumber(json, "epipolar_mean_px"), 0.3) << json;
  EXPECT_GE(jsonNumber(json, "pairs_used"), 12) << json;
  EXPECT_EQ(jsonNumber(json, "image_width"), 640);
  EXPECT_TRUE(fs::exists(dir / "out" / "rectified_check.png"));
  const cv::Mat check = cv::imread((dir / "out" / "rectified_check.png").string());
  EXPECT_EQ(check.size(), cv::Size(1280, 480));
  auto rect = drivers::loadStereoRectification((dir / "out" / "stereo.yaml").string(), 640, 480);
  ASSERT_TRUE(rect.isOk()) << rect.status().message();
  EXPECT_NEAR(rect->calib.baseline_m, jsonNumber(json, "baseline_m"), 1e-5);
}

TEST(CliCalibrate, TwoFoldersOfRenderedPairsGiveTheRenderedCameras) {
  const fs::path dir = freshTestDir("svslam_cli_calib_");
  writeScene(dir, 9, true);
  const fs::path file = dir / "mine.json";
  const int code =
      runSvslam("calibrate --left " + (dir / "L").string() + " --right " + (dir / "R").string() +
                    " --square 0.03 --out " + (dir / "out").string() + " --output " + file.string(),
                dir / "out.json", dir / "err.txt");
  ASSERT_EQ(code, 0) << slurp(dir / "err.txt");
  const std::string json = slurp(dir / "out.json");
  EXPECT_NEAR(jsonNumber(json, "baseline_m"), 0.1, 0.001) << json;
  EXPECT_EQ(jsonNumber(json, "pairs_used"), 9) << json;
  auto c = drivers::readStereoCalibrationFile(file.string());
  ASSERT_TRUE(c.isOk()) << c.status().message();
  EXPECT_NEAR(c->K1.at<double>(0, 0), ChessboardScene{}.fx, 2.5);
  EXPECT_NEAR(c->K1.at<double>(0, 2), ChessboardScene{}.cx, 2.0);
  EXPECT_FALSE(fs::exists(dir / "out" / "stereo.yaml"));
}

// Runs calibrate with `args`; expects failure, `message` on stderr and no output folder.
void expectRefused(const fs::path& dir, const std::string& args, const std::string& message) {
  const fs::path out = dir / "out";
  const int code =
      runSvslam("calibrate " + args + " --out " + out.string(), dir / "out.json", dir / "err.txt");
  EXPECT_NE(code, 0) << args;
  const std::string err = slurp(dir / "err.txt");
  EXPECT_NE(err.find(message), std::string::npos) << args << "\n" << err;
  EXPECT_FALSE(fs::exists(out)) << args;
  EXPECT_EQ(slurp(dir / "out.json"), "") << args;
}

TEST(CliCalibrate, BadInputsAreRefusedAndNothingIsWritten) {
  const fs::path dir = freshTestDir("svslam_cli_calib_");
  expectRefused(dir, "--images " + (dir / "nowhere").string(), "no such folder");
  const fs::path imgs = dir / "imgs";
  fs::create_directories(imgs);
  writeScene(imgs, 6, false);
  expectRefused(dir, "--images " + imgs.string() + " --board 10x7",
                "10x7 board (inner corners) was found in none of the 6 pairs");
  expectRefused(dir, "--images " + imgs.string() + " --min-pairs 7",
                "too few usable pairs: 6 of 6, need 7");
  expectRefused(dir, "--images " + imgs.string() + " --square 0", "square_m must be in");
  expectRefused(dir, "--images " + imgs.string() + " --left " + imgs.string(),
                "exactly one of --images, --left/--right, --source");
  fs::remove(imgs / "right03.png");
  expectRefused(dir, "--images " + imgs.string(),
                "unequal left/right images in " + imgs.string() +
                    ": 6 left and 5 right; left03.png has no right03.png");
  cv::Mat small(240, 320, CV_8U, cv::Scalar(128));
  ASSERT_TRUE(cv::imwrite((imgs / "right03.png").string(), small));
  expectRefused(dir, "--images " + imgs.string(),
                "mixed image sizes: 03.png left is 640x480, right is 320x240");
  const fs::path blank = dir / "blank";
  fs::create_directories(blank);
  for (const char* n : {"left1.png", "right1.png", "left2.png", "right2.png"})
    ASSERT_TRUE(cv::imwrite((blank / n).string(), cv::Mat(480, 640, CV_8U, cv::Scalar(90))));
  expectRefused(dir, "--images " + blank.string(), "was found in none of the 2 pairs");
  const fs::path other = dir / "other";
  fs::create_directories(other);
  ASSERT_TRUE(cv::imwrite((other / "scene.png").string(), small));
  expectRefused(dir, "--images " + other.string(), "no left*/right* images in");
  expectRefused(dir, "--source kitti:/nowhere", "needs a v4l2: or libcamera: source");
}

}  // namespace
}  // namespace svslam::test

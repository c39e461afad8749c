// The svslam executable end to end: outputs, JSON, and a clear error with a non-zero exit for
// every kind of bad input (never a crash).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "cli_helpers.hpp"
#include "drivers/files/image_io.hpp"
#include "drivers/files/opencv_view.hpp"
#include "drivers/synthetic/synthetic_pair.hpp"
#include "pipeline/cli/json_writer.hpp"

namespace fs = std::filesystem;
using svslam::test::slurp;

namespace {

struct CliRun {
  int code = -1;
  std::string out, err;
};

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = svslam::test::freshTestDir("svslam_cli_");
    svslam::drivers::SyntheticPairParams p;
    p.width = 160;
    p.height = 120;
    p.d_near_px = 20;
    auto pair = svslam::drivers::makeSyntheticPair(p);
    ASSERT_TRUE(pair.isOk());
    writeGrey(path("l.png"), pair->left);
    writeGrey(path("r.png"), pair->right);
    ASSERT_TRUE(svslam::drivers::writePfm(path("gt.pfm"), pair->gt_disparity_px.cview()).isOk());
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static void writeGrey(const std::string& p, const svslam::ImageU8& img) {
    const cv::Mat m = svslam::drivers::asMat(img);
    ASSERT_TRUE(cv::imwrite(p, m));
  }
  CliRun run(const std::string& args) const {
    CliRun r;
    r.code = svslam::test::runSvslam(args, path("stdout.txt"), path("stderr.txt"));
    r.out = slurp(path("stdout.txt"));
    r.err = slurp(path("stderr.txt"));
    return r;
  }
  // A failing run: exit code 1 or 2 (not a crash), a message on stderr containing `needle`.
  void expectError(const std::string& args, const std::string& needle) const {
    const CliRun r = run(args);
    EXPECT_TRUE(r.code == 1 || r.code == 2) << args << " exited " << r.code << "\n" << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\nstderr: " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  fs::path dir_;
};

TEST_F(Cli, DisparityWritesOutputsAndJson) {
  const CliRun r = run("disparity --left " + path("l.png") + " --right " + path("r.png") +
                       " --max-disp 32 --repeat 3 --out " + path("d.pfm") + " --sigma " +
                       path("s.pfm") + " --color " + path("c.png"));
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* key : {"\"width\": 160", "\"height\": 120", "\"method\": \"census\"",
                          "\"threads\": 1", "\"median_ms\"", "\"valid_fraction\""})
    EXPECT_NE(r.out.find(key), std::string::npos) << key << " in " << r.out;
  auto d = svslam::drivers::readPfm(path("d.pfm"));
  ASSERT_TRUE(d.isOk());
  int inf = 0;
  for (int y = 0; y < d->height(); ++y)
    for (int x = 0; x < d->width(); ++x) {
      EXPECT_FALSE(std::isnan((*d)(x, y)));
      inf += std::isinf((*d)(x, y));
    }
  EXPECT_GT(inf, 0);  // occlusions and the left border are invalid (+inf)
  EXPECT_TRUE(fs::exists(path("s.pfm")));
  EXPECT_TRUE(fs::exists(path("c.png")));
  // KITTI png: uint16 = d * 256, 0 invalid; matches the pfm.
  ASSERT_EQ(run("disparity --left " + path("l.png") + " --right " + path("r.png") +
                " --max-disp 32 --out " + path("d.png"))
                .code,
            0);
  cv::Mat png = cv::imread(path("d.png"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(png.type(), CV_16U);
  for (int y = 0; y < png.rows; y += 7)
    for (int x = 0; x < png.cols; x += 5) {
      const float v = (*d)(x, y);
      const int p = png.at<std::uint16_t>(y, x);
      if (std::isinf(v))
        EXPECT_EQ(p, 0);
      else
        EXPECT_NEAR(p / 256.0, v, 1.0 / 256);
    }
  // Threads do not change the result.
  ASSERT_EQ(run("disparity --left " + path("l.png") + " --right " + path("r.png") +
                " --max-disp 32 --threads 2 --out " + path("d2.pfm"))
                .code,
            0);
  EXPECT_EQ(slurp(path("d.pfm")), slurp(path("d2.pfm")));
}

TEST_F(Cli, EvalDisparityScoresAgainstGroundTruth) {
  const CliRun r = run("eval-disparity --gt " + path("gt.pfm") + " --left " + path("l.png") +
                       " --right " + path("r.png") + " --max-disp 32");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* key : {"bad05_valid_pct", "bad1_valid_pct", "bad2_valid_pct", "bad3_valid_pct",
                          "bad1_all_pct", "density_pct", "mae_valid_px"})
    EXPECT_NE(r.out.find(key), std::string::npos) << key;
  // Scoring the ground truth against itself: no error, full density.
  const CliRun self = run("eval-disparity --gt " + path("gt.pfm") + " --disp " + path("gt.pfm"));
  ASSERT_EQ(self.code, 0) << self.err;
  EXPECT_NE(self.out.find("\"bad05_valid_pct\": 0.0000"), std::string::npos) << self.out;
  EXPECT_NE(self.out.find("\"density_pct\": 100.0000"), std::string::npos) << self.out;
}

TEST_F(Cli, BuiltInSyntheticSourceRunsWithoutData) {
  const CliRun r = run("disparity --synthetic-size 200x150");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"source\": \"synthetic\""), std::string::npos);
}

TEST_F(Cli, HelpExplainsEveryCommand) {
  EXPECT_EQ(run("--help").code, 0);
  for (const char* c : {"disparity", "eval-disparity", "fit-sigma"}) {
    const CliRun r = run(std::string(c) + " --help");
    EXPECT_EQ(r.code, 0) << c;
    EXPECT_NE(r.out.find("--threads"), std::string::npos) << c;
  }
  EXPECT_EQ(run("eval-trajectory --help").code, 0);
  const CliRun d = run("disparity --help");
  for (const char* o : {"--left", "--right", "--max-disp", "--min-disp", "--method", "--window",
                        "--threads", "--repeat", "--out", "--sigma", "--color"})
    EXPECT_NE(d.out.find(o), std::string::npos) << o;
}

TEST_F(Cli, BadInputsGiveClearErrors) {
  const std::string pair = " --left " + path("l.png") + " --right " + path("r.png");
  expectError(
      "disparity --left " + path("missing.png") + " --right " + path("r.png") + " --max-disp 16",
      "missing.png");
  expectError("disparity" + pair + " --max-disp 0", "--max-disp");
  expectError("disparity" + pair + " --max-disp 160", "max_disp");
  expectError("disparity" + pair + " --max-disp 16 --method ssd", "unknown method");
  expectError("disparity" + pair + " --max-disp 16 --window 4x4", "odd");
  expectError("disparity" + pair + " --max-disp 16 --census 9x9", "64 neighbours");
  expectError("disparity" + pair + " --max-disp 16 --bogus 1", "unknown option --bogus");
  expectError("disparity" + pair + " --max-disp abc", "not an integer");
  expectError("disparity" + pair + " --max-disp 16 --out " + path("d.txt"), ".pfm or .png");
  expectError("disparity --left " + path("l.png") + " --max-disp 16", "both --left and --right");
  expectError("frobnicate", "unknown command");
  // Left and right of different sizes.
  svslam::ImageU8 small(100, 120);
  writeGrey(path("small.png"), small);
  expectError(
      "disparity --left " + path("l.png") + " --right " + path("small.png") + " --max-disp 16",
      "differ in size");
  // Empty, garbage and truncated files.
  { std::ofstream(path("empty.png")); }
  expectError(
      "disparity --left " + path("empty.png") + " --right " + path("r.png") + " --max-disp 16",
      "empty.png");
  { std::ofstream(path("garbage.png")) << "this is not an image"; }
  expectError(
      "disparity --left " + path("garbage.png") + " --right " + path("r.png") + " --max-disp 16",
      "garbage.png");
  const std::string png = slurp(path("l.png"));
  { std::ofstream(path("trunc.png"), std::ios::binary) << png.substr(0, png.size() / 2); }
  expectError(
      "disparity --left " + path("trunc.png") + " --right " + path("r.png") + " --max-disp 16",
      "trunc.png");
  // Output folder that does not exist: error naming the path; nothing half-written.
  expectError("disparity" + pair + " --max-disp 16 --out " + path("no/such/dir/d.pfm"), "d.pfm");
  expectError("eval-disparity --gt " + path("missing.pfm") + " --disp " + path("gt.pfm"),
              "missing.pfm");
  expectError("eval-disparity --dataset " + path("nowhere"), "nowhere");
}

TEST_F(Cli, EvalTrajectoryScoresAndRejectsBadInput) {
  {
    std::ofstream f(path("gt.txt"));
    for (int i = 0; i < 30; ++i) f << "1 0 0 0 0 1 0 0 0 0 1 " << i << "\n";  // straight along z
  }
  {
    std::ofstream f(path("est.txt"));
    for (int i = 0; i < 30; ++i) f << "1 0 0 0 0 1 0 0 0 0 1 " << 1.02 * i << "\n";  // 2 % long
  }
  const CliRun r = run("eval-trajectory --gt " + path("gt.txt") + " --est " + path("est.txt") +
                       " --segments 5 --step 1");
  ASSERT_EQ(r.code, 0) << r.err;
  // KITTI devkit: a segment ends at the first frame farther than L (here 6 m for L = 5 m) and its
  // error is divided by L: 2 % of 6 m over 5 m = 2.4 %.
  EXPECT_NE(r.out.find("\"t_err_pct\": 2.4000"), std::string::npos) << r.out;
  for (const char* key :
       {"ate_rmse_m", "rpe_trans_rmse_m", "final_pos_err_m", "final_att_err_deg", "segments"})
    EXPECT_NE(r.out.find(key), std::string::npos) << key;
  expectError("eval-trajectory --gt " + path("gt.txt") + " --est " + path("none.txt"), "none.txt");
  expectError(
      "eval-trajectory --gt " + path("gt.txt") + " --est " + path("est.txt") + " --align sim2",
      "unknown alignment");
  // The estimate is 2 % too long: Sim(3) alignment takes the scale out.
  const CliRun s = run("eval-trajectory --gt " + path("gt.txt") + " --est " + path("est.txt") +
                       " --align sim3");
  ASSERT_EQ(s.code, 0) << s.err;
  EXPECT_NE(s.out.find("\"ate_rmse_m\": 0.0000"), std::string::npos) << s.out;
  EXPECT_NE(s.out.find("\"align_scale\": 0.980392"), std::string::npos) << s.out;
  expectError(
      "eval-trajectory --gt " + path("gt.txt") + " --est " + path("est.txt") + " --segments 5,x",
      "not a number");
  { std::ofstream(path("short.txt")) << "1 0 0 0 0 1 0 0 0 0 1 0\n"; }
  expectError("eval-trajectory --gt " + path("gt.txt") + " --est " + path("short.txt"),
              "paired by index");
  expectError(
      "eval-trajectory --gt " + path("gt.txt") + " --est " + path("est.txt") + " --max-dt -1",
      "--max-dt: -1 is negative");
  expectError("eval-trajectory --gt " + path("gt.txt") + " --est " + path("est.txt") +
                  " --euroc " + path("no_euroc"),
              "no_euroc/mav0/cam0/sensor.yaml");
  expectError("eval-trajectory --gt " + path("gt.txt") + " --est " + path("est.txt") +
                  " --euroc " + path("x") + " --body-to-cam " + path("y"),
              "use one");
  {
    std::ofstream f(path("skew.txt"));  // line 2: a scaled, not orthonormal, 3x3 part
    for (int i = 0; i < 30; ++i)
      f << (i == 1 ? "2 0 0 0 0 1 0 0 0 0 1 " : "1 0 0 0 0 1 0 0 0 0 1 ") << i << "\n";
  }
  expectError("eval-trajectory --gt " + path("gt.txt") + " --est " + path("skew.txt"),
              "skew.txt:2: the 3x3 part is not a rotation");
}

TEST_F(Cli, EvalTrajectorySegmentsWithoutDataAreNull) {
  {
    std::ofstream f(path("gt.txt"));
    for (int i = 0; i < 30; ++i) f << "1 0 0 0 0 1 0 0 0 0 1 " << i << "\n";  // 29 m
  }
  const CliRun r = run("eval-trajectory --gt " + path("gt.txt") + " --est " + path("gt.txt") +
                       " --segments 5,100 --step 1");
  ASSERT_EQ(r.code, 0) << r.err;
  // 5 m: scored; 100 m: longer than the path, so no drift (null and why), not 0 %.
  EXPECT_NE(r.out.find("\"length_m\": 5.00, \"count\": 24, \"t_err_pct\": 0.0000"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("\"length_m\": 100.00, \"count\": 0, \"t_err_pct\": null, "
                       "\"r_err_deg_per_m\": null, \"reason\": \"the ground-truth path (29.00 m) "
                       "is shorter than 100.00 m\""),
            std::string::npos)
      << r.out;
  const CliRun none = run("eval-trajectory --gt " + path("gt.txt") + " --est " + path("gt.txt") +
                          " --segments 100 --step 1");
  ASSERT_EQ(none.code, 0) << none.err;
  EXPECT_NE(none.out.find("\"t_err_pct\": null"), std::string::npos) << none.out;
  EXPECT_NE(none.out.find("\"t_err_reason\""), std::string::npos) << none.out;
}

TEST_F(Cli, FailedWriteOfTheResultIsAnError) {
  // The JSON result lost (disk full, stdout closed) is a failure, not exit 0.
  const std::string cmd = std::string(SVSLAM_CLI) + " disparity --left " + path("l.png") +
                          " --right " + path("r.png") + " --max-disp 32";
  if (fs::exists("/dev/full")) {
    const int code =
        svslam::test::exitCode(std::system((cmd + " > /dev/full 2> " + path("err.txt")).c_str()));
    EXPECT_EQ(code, 1) << slurp(path("err.txt"));
    EXPECT_NE(slurp(path("err.txt")).find("cannot write the result to stdout"), std::string::npos)
        << slurp(path("err.txt"));
  }
  const int closed =
      svslam::test::exitCode(std::system((cmd + " >&- 2> " + path("err.txt")).c_str()));
  EXPECT_EQ(closed, 1) << slurp(path("err.txt"));
  EXPECT_NE(slurp(path("err.txt")).find("cannot write the result to stdout"), std::string::npos)
      << slurp(path("err.txt"));
  EXPECT_EQ(
      run("disparity --left " + path("l.png") + " --right " + path("r.png") + " --max-disp 32")
          .code,
      0);
}

TEST_F(Cli, MessagesAgreeWithTheChecks) {
  const std::string pair = " --left " + path("l.png") + " --right " + path("r.png");
  // Each side of the census window is odd and at least 3: 1x3 and 1x63 alike.
  expectError("disparity" + pair + " --max-disp 16 --census 1x3",
              "each side must be odd and at least 3");
  expectError("disparity" + pair + " --max-disp 16 --census 1x63",
              "each side must be odd and at least 3");
  // Too large is not "not of the form WxH".
  expectError("disparity --synthetic-size 100000x100000", "is too large (each side at most 8192)");
  expectError("disparity --synthetic-size 100x", "not of the form WxH");
}

TEST(JsonWriter, InvalidUtf8BecomesTheReplacementCharacter) {
  using svslam::cli::jsonEscape;
  EXPECT_EQ(jsonEscape("a\xff"
                       "b"),
            "\"a\\ufffdb\"");
  EXPECT_EQ(jsonEscape("\xc3\xa9t\xc3\xa9"), "\"\xc3\xa9t\xc3\xa9\"");  // valid UTF-8 kept
  EXPECT_EQ(jsonEscape("\xe2\x82\xac"), "\"\xe2\x82\xac\"");            // 3 bytes (euro sign)
  EXPECT_EQ(jsonEscape("\xf0\x9f\x98\x80"), "\"\xf0\x9f\x98\x80\"");    // 4 bytes
  EXPECT_EQ(jsonEscape("\xc3"), "\"\\ufffd\"");                         // truncated
  EXPECT_EQ(jsonEscape("\xc0\xaf"), "\"\\ufffd\\ufffd\"");              // overlong '/'
  EXPECT_EQ(jsonEscape("\xed\xa0\x80"), "\"\\ufffd\\ufffd\\ufffd\"");   // a surrogate
  EXPECT_EQ(jsonEscape("q\"\\\n\x01"), "\"q\\\"\\\\\\n\\u0001\"");
}

TEST_F(Cli, InvalidUtf8InAPathKeepsTheJsonValid) {
  std::ofstream(path("c.yaml")) << "dense_stereo: {enabled: false}\nmap: {enabled: false}\n";
  const std::string out = path("out\xff\xfe");
  const CliRun r = run("run --source synthetic:width=320,height=240,frames=2 --config " +
                       path("c.yaml") + " --out '" + out + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\\ufffd\\ufffd"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find('\xff'), std::string::npos) << r.out;
}

TEST_F(Cli, ColourInputIsConvertedToGrey) {
  cv::Mat l = cv::imread(path("l.png"), cv::IMREAD_GRAYSCALE), lc;
  cv::cvtColor(l, lc, cv::COLOR_GRAY2BGR);
  ASSERT_TRUE(cv::imwrite(path("lc.png"), lc));
  ASSERT_EQ(run("disparity --left " + path("lc.png") + " --right " + path("r.png") +
                " --max-disp 32 --out " + path("a.pfm"))
                .code,
            0);
  ASSERT_EQ(run("disparity --left " + path("l.png") + " --right " + path("r.png") +
                " --max-disp 32 --out " + path("b.pfm"))
                .code,
            0);
  EXPECT_EQ(slurp(path("a.pfm")), slurp(path("b.pfm")));
}

}  // namespace

// svslam calibrate: chessboard stereo calibration from image pairs on disk or from the live
// cameras -> the calibration file of the v4l2:/libcamera: sources, a rectified check image and
// quality figures (JSON on stdout). Nothing is written unless the calibration succeeded.
#include <poll.h>
#include <unistd.h>

#include <climits>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "drivers/calib/calibration_pairs.hpp"
#include "drivers/calib/stereo_calibrator.hpp"
#include "drivers/camera/raw_stereo_capture.hpp"
#include "drivers/files/image_io.hpp"
#include "drivers/files/opencv_view.hpp"
#include "drivers/files/stereo_calibration_file.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "pipeline/tools/calibration_capture.hpp"

namespace svslam::cli {
namespace {

namespace fs = std::filesystem;

// Interactive trigger: a line on stdin grabs the next pair; "q" or end of input stops.
Trigger stdinTrigger() {
  pollfd p{STDIN_FILENO, POLLIN, 0};
  if (::poll(&p, 1, 0) <= 0) return Trigger::kNone;
  std::string line;
  if (!std::getline(std::cin, line)) return Trigger::kStop;
  return line == "q" ? Trigger::kStop : Trigger::kGrab;
}

Status fromFolders(const ArgParser& p, drivers::StereoCalibrator& cal, cv::Mat& check_l,
                   cv::Mat& check_r) {
  auto pairs = p.has("images") ? drivers::listCalibrationPairs(p.get("images"))
                               : drivers::listCalibrationPairs(p.get("left"), p.get("right"));
  if (!pairs) return pairs.status();
  for (const auto& pair : *pairs) {
    auto l = drivers::loadGrey(pair.left);
    if (!l) return l.status();
    auto r = drivers::loadGrey(pair.right);
    if (!r) return r.status();
    bool accepted = false;
    if (Status s = cal.addPair(drivers::asMat(*l), drivers::asMat(*r), pair.name, accepted); !s)
      return s;
    if (accepted && check_l.empty()) {
      drivers::asMat(*l).copyTo(check_l);
      drivers::asMat(*r).copyTo(check_r);
    }
  }
  return Status::ok();
}

// Writes `img` as PNG through a temporary in the same folder renamed over `path`.
Status writePngAtomically(const fs::path& path, const cv::Mat& img) {
  const fs::path tmp = path.parent_path() / (".tmp-" + path.filename().string());
  std::error_code ec;
  bool ok = false;
  try {
    ok = cv::imwrite(tmp.string(), img);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (ok) fs::rename(tmp, path, ec);
  if (!ok || ec) {
    fs::remove(tmp, ec);
    return Status::ioError("cannot write " + path.string());
  }
  return Status::ok();
}

std::string rejectedJson(const std::vector<drivers::PairRejection>& rejected) {
  std::string s = "[";
  for (std::size_t i = 0; i < rejected.size(); ++i) {
    if (i) s += ',';
    s += "{\"pair\":";
    s += jsonEscape(rejected[i].pair);
    s += ",\"reason\":";
    s += jsonEscape(rejected[i].reason);
    s += '}';
  }
  return s + "]";
}

std::string matJson(const cv::Mat& m) {
  std::string s = "[";
  char buf[32];
  for (int i = 0; i < static_cast<int>(m.total()); ++i) {
    std::snprintf(buf, sizeof buf, "%s%.6g", i ? "," : "", m.at<double>(i));
    s += buf;
  }
  return s + "]";
}

}  // namespace

int runCalibrate(const std::vector<std::string>& args) {
  ArgParser p(
      "calibrate",
      "Stereo chessboard calibration: corners (findChessboardCorners + cornerSubPix),\n"
      "calibrateCamera per camera, stereoCalibrate (joint refinement by default),\n"
      "stereoRectify (Bouguet). Writes the calibration file of the v4l2:/libcamera:\n"
      "sources and rectified_check.png into --out; prints JSON: RMS per camera and pair,\n"
      "rectified epipolar error, image size, pairs used and rejected (with the reason).\n"
      "Input: --images DIR (leftX / rightX names), --left DIR --right DIR (same names), or\n"
      "--source v4l2:...|libcamera:... (live; Enter grabs a pair, q ends).");
  p.addOption("images", "DIR",
              "one folder: left<X> pairs with right<X> (e.g. left01.jpg, right01.jpg)");
  p.addOption("left", "DIR", "with --right: folders of left / right images paired by file name");
  p.addOption("right", "DIR", "see --left");
  p.addOption("source", "SPEC", "live cameras: a v4l2: or libcamera: spec (calib= not needed)");
  p.addOption("grab-every", "N", "live: grab every N-th pair without asking (0 = on Enter)", "0");
  p.addOption("pairs", "K", "live: stop after K accepted pairs, 1..1000", "15");
  p.addOption("max-frames", "N", "live: stop after N pairs read (0 = no limit)", "0");
  p.addOption("board", "CxR", "inner corners per row x per column of the chessboard", "9x6");
  p.addOption("square", "M", "side of one square, metres", "0.025");
  p.addOption("min-sharpness", "S",
              "reject a view whose Laplacian variance in the board box is below S (grey^2)", "200");
  p.addOption("min-motion", "PX",
              "reject a pair whose corners moved less than PX from an accepted one", "2");
  p.addOption("min-pairs", "N", "usable pairs needed, 3..1000", "6");
  p.addOption("min-coverage", "F", "fraction of the 3x3 image cells the corners must touch, 0..1",
              "0.75");
  p.addOption("max-view-rms", "PX", "reject (and recalibrate without) a pair above this RMS, px",
              "1.0");
  p.addFlag("fix-intrinsic",
            "stereoCalibrate with CALIB_FIX_INTRINSIC instead of the joint refinement");
  p.addOption("out", "DIR", "output folder (created if missing)", "svslam_calib");
  p.addOption("output", "FILE", "calibration file (.yaml, .xml or .json); default DIR/stereo.yaml");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("calibrate", s); };

  const int inputs = (p.has("images") ? 1 : 0) + (p.has("left") || p.has("right") ? 1 : 0) +
                     (p.has("source") ? 1 : 0);
  if (inputs != 1)
    return fail(Status::invalidArgument("give exactly one of --images, --left/--right, --source"));
  if (p.has("left") != p.has("right"))
    return fail(Status::invalidArgument("--left and --right go together"));
  drivers::StereoCalibrationParams cp;
  if (Status s = p.getSize("board", cp.board_cols, cp.board_rows, false); !s) return fail(s);
  struct {
    const char* name;
    double* field;
  } doubles[] = {{"square", &cp.square_m},
                 {"min-sharpness", &cp.min_sharpness},
                 {"min-motion", &cp.min_motion_px},
                 {"min-coverage", &cp.min_coverage},
                 {"max-view-rms", &cp.max_view_rms_px}};
  for (const auto& d : doubles) {
    auto v = p.getDouble(d.name);
    if (!v) return fail(v.status());
    *d.field = *v;
  }
  auto min_pairs = p.getInt("min-pairs", 3, 1000);
  if (!min_pairs) return fail(min_pairs.status());
  cp.min_pairs = *min_pairs;
  cp.fix_intrinsic = p.flag("fix-intrinsic");
  drivers::StereoCalibrator cal(cp);
  if (!cal.initStatus()) return fail(cal.initStatus());

  cv::Mat check_l, check_r;
  if (p.has("source")) {
    LiveCollectOptions lo;
    auto every = p.getInt("grab-every", 0, INT_MAX);
    if (!every) return fail(every.status());
    auto pairs = p.getInt("pairs", 1, 1000);
    if (!pairs) return fail(pairs.status());
    auto max_frames = p.getInt("max-frames", 0, INT_MAX);
    if (!max_frames) return fail(max_frames.status());
    lo.grab_every = *every;
    lo.pairs = *pairs;
    lo.max_frames = *max_frames;
    auto cam = drivers::openRawStereoCapture(p.get("source"));
    if (!cam) return fail(Status(cam.status().code(), "--source: " + cam.status().message()));
    if (lo.grab_every == 0)
      std::fprintf(stderr, "svslam calibrate: Enter grabs a pair, q + Enter ends\n");
    LiveCollectStats stats;
    if (Status s = collectLivePairs(
            **cam, cal, lo, stdinTrigger,
            [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); }, check_l,
            check_r, stats);
        !s)
      return fail(s);
  } else if (Status s = fromFolders(p, cal, check_l, check_r); !s) {
    return fail(s);
  }
  auto res = cal.calibrate();
  if (!res) return fail(res.status());

  const fs::path out_dir(p.get("out"));
  const fs::path calib_file = p.has("output") ? fs::path(p.get("output")) : out_dir / "stereo.yaml";
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) return fail(Status::ioError("cannot create " + out_dir.string() + ": " + ec.message()));
  const fs::path check_png = out_dir / "rectified_check.png";
  if (Status s =
          writePngAtomically(check_png, drivers::renderRectifiedCheck(*res, check_l, check_r));
      !s)
    return fail(s);
  if (Status s = drivers::writeStereoCalibrationFile(calib_file.string(), res->file); !s) {
    fs::remove(check_png, ec);
    return fail(s);
  }

  std::string used = "[";
  for (std::size_t i = 0; i < res->used.size(); ++i) {
    if (i) used += ',';
    used += jsonEscape(res->used[i]);
  }
  used += "]";
  JsonObject j;
  j.add("calibration", calib_file.string())
      .add("check_image", check_png.string())
      .add("image_width", res->file.width)
      .add("image_height", res->file.height)
      .add("board", p.get("board"))
      .add("square_m", cp.square_m, 6)
      .add("stereo_mode", cp.fix_intrinsic ? "fix_intrinsic" : "joint")
      .add("rms_left_px", res->rms_left_px)
      .add("rms_right_px", res->rms_right_px)
      .add("rms_pair_px", res->rms_pair_px)
      .add("sigma_principal_point_left_px", res->sigma_principal_point_left_px)
      .add("sigma_f_left_rel", res->sigma_f_left_rel, 6)
      .add("epipolar_mean_px", res->epipolar_mean_px)
      .add("epipolar_max_px", res->epipolar_max_px)
      .add("coverage_left", res->coverage_left, 3)
      .add("coverage_right", res->coverage_right, 3)
      .add("baseline_m", res->baseline_m, 6)
      .add("rectified_f_px", res->P1.at<double>(0, 0), 3)
      .add("rectified_cx_px", res->P1.at<double>(0, 2), 3)
      .add("rectified_cy_px", res->P1.at<double>(1, 2), 3)
      .addRaw("K1", matJson(res->file.K1))
      .addRaw("D1", matJson(res->file.D1))
      .addRaw("K2", matJson(res->file.K2))
      .addRaw("D2", matJson(res->file.D2))
      .addRaw("T_m", matJson(res->file.T))
      .add("pairs_used", static_cast<std::int64_t>(res->used.size()))
      .addRaw("used", used)
      .add("pairs_rejected", static_cast<std::int64_t>(res->rejected.size()))
      .addRaw("rejected", rejectedJson(res->rejected));
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace svslam::cli

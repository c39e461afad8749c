// svslam: the one executable, with subcommands.
#include <signal.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "pipeline/cli/commands.hpp"

namespace {

constexpr const char* kUsage =
    "usage: svslam <command> [options]\n"
    "\n"
    "svslam: real-time stereo-vision SLAM (dense census/SAD stereo, EKF, LCM).\n"
    "\n"
    "commands:\n"
    "  disparity        dense disparity of a rectified stereo pair (census or SAD correlation)\n"
    "  eval-disparity   score a disparity map (given or computed) against ground truth\n"
    "  fit-sigma        fit the curvature -> sigma_d model of the disparity on ground truth\n"
    "  run              visual odometry on a stereo sequence (default: built-in synthetic flight)\n"
    "  config           print the documented configuration of 'run' at its defaults (--defaults)\n"
    "  eval-trajectory  drift, ATE and RPE of a trajectory against ground truth (KITTI/TUM/EuRoC)\n"
    "  eval-dem         accuracy and coverage of an elevation map (GeoTIFF) against ground truth\n"
    "  train-vocabulary ORB bag-of-words vocabulary (loop closing) from a set of images\n"
    "  plot             pictures of a run (PNG + SVG): trajectory, altitude, landmarks, latency\n"
    "  calibrate        stereo chessboard calibration (image pairs or live cameras) -> calib file\n"
#ifdef SVSLAM_HAVE_LISTEN
    "  listen           print every svslam message on LCM (poses, stats, map, corrections,\n"
    "                   commands, images) as JSON lines\n"
#endif
    "\n"
    "Run 'svslam <command> --help' for the options of a command.\n";

// Runs the command `cmd`; -1 when there is no such command.
int dispatch(const std::string& cmd, const std::vector<std::string>& args) {
  if (cmd == "--help" || cmd == "-h" || cmd == "help") {
    std::fputs(kUsage, stdout);
    return 0;
  }
  if (cmd == "disparity") return svslam::cli::runDisparity(args);
  if (cmd == "eval-disparity") return svslam::cli::runEvalDisparity(args);
  if (cmd == "fit-sigma") return svslam::cli::runFitSigma(args);
  if (cmd == "run") return svslam::cli::runPipeline(args);
  if (cmd == "config") return svslam::cli::runConfig(args);
  if (cmd == "eval-trajectory") return svslam::cli::runEvalTrajectory(args);
  if (cmd == "eval-dem") return svslam::cli::runEvalDem(args);
  if (cmd == "train-vocabulary") return svslam::cli::runTrainVocabulary(args);
  if (cmd == "plot") return svslam::cli::runPlot(args);
  if (cmd == "calibrate") return svslam::cli::runCalibrate(args);
#ifdef SVSLAM_HAVE_LISTEN
  if (cmd == "listen") return svslam::cli::runListen(args);
#endif
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  // A file size limit (RLIMIT_FSIZE, systemd's LimitFSIZE=) then makes a write fail with EFBIG,
  // reported like a full disk (naming the file), instead of killing the process with a core.
  ::signal(SIGXFSZ, SIG_IGN);
  const std::string cmd = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  int code = -1;
  try {
    code = dispatch(cmd, args);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "svslam %s: out of memory\n", cmd.c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "svslam %s: internal error: %s\n", cmd.c_str(), e.what());
    return 1;
  }
  if (code < 0) {
    std::fprintf(stderr, "svslam: unknown command '%s'\n\n%s", cmd.c_str(), kUsage);
    return 2;
  }
  // The results go to stdout: a write that failed (disk full, closed pipe or descriptor) is an
  // error, not a success with the output lost.
  errno = 0;
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    const int err = errno;
    std::fprintf(stderr, "svslam %s: cannot write the result to stdout: %s\n", cmd.c_str(),
                 err ? std::strerror(err) : "write error");
    return code == 0 ? 1 : code;
  }
  return code;
}

// svslam eval-trajectory: drift, ATE and RPE of an estimated trajectory against ground truth.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/files/trajectory_io.hpp"
#include "drivers/files/yaml_lists.hpp"
#include "drivers/source/stereo_source.hpp"
#include "eval/trajectory_metrics.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "pipeline/tools/stereo_case.hpp"

namespace svslam::cli {
namespace {

std::string vec3Json(const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "[%.6f, %.6f, %.6f]", v.x(), v.y(), v.z());
  return buf;
}

}  // namespace

int runEvalTrajectory(const std::vector<std::string>& args) {
  ArgParser p(
      "eval-trajectory",
      "Scores an estimated camera trajectory against ground truth and prints JSON: KITTI\n"
      "devkit segment drift (translation %, rotation deg/m) per length and on average, ATE\n"
      "RMSE after alignment, frame-to-frame RPE, final position and attitude error, and the\n"
      "rotation about the first camera centre that best lays the estimate on the ground truth\n"
      "(start_rotation_*: an early attitude error every later pose inherits) with the ATE and\n"
      "final error left after it (the trajectory's shape error).\n"
      "Files: KITTI poses (3x4 per line, paired by index) or TUM (t tx ty tz qx qy qz qw,\n"
      "paired by nearest stamp); EuRoC body ground truth becomes cam0 with --body-to-cam.");
  p.addOption("gt", "FILE", "ground-truth trajectory (KITTI or TUM)", std::nullopt, true);
  p.addOption("est", "FILE", "estimated trajectory (KITTI or TUM)", std::nullopt, true);
  p.addOption("segments", "L1,L2,...", "segment lengths in metres",
              "100,200,300,400,500,600,700,800");
  p.addOption("step", "N", "first frames of segments every N frames (KITTI devkit: 10)", "10");
  p.addOption("align", "se3|sim3|none",
              "se3: Umeyama rigid alignment; sim3: Umeyama with scale (estimates up to scale, "
              "monocular); none: both relative to their first pose",
              "se3");
  p.addOption("max-dt", "S", "largest stamp difference when pairing TUM files, seconds", "0.02");
  p.addOption("cov", "FILE",
              "pose covariances of the estimate (svslam run's pose_covariance.txt: 36 numbers "
              "per estimate line, [rot rad, trans m]): adds NEES and the share of frames whose "
              "errors are within 2 sigma");
  p.addOption("body-to-cam", "SENSOR_YAML",
              "EuRoC cam0 sensor.yaml: ground truth T_W_B becomes T_W_B * T_BS (the raw cam0)");
  p.addOption("euroc", "DIR",
              "EuRoC folder (mav0/cam0, mav0/cam1): ground truth T_W_B becomes the rectified "
              "left camera that `svslam run --source euroc:DIR` tracks, T_W_B * T_BS * "
              "[R_rect^T | 0] (the score of svslam's EuRoC runs; not with --body-to-cam)");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("eval-trajectory", s); };

  TrajectoryEvalParams params;
  params.segment_lengths_m.clear();
  for (const auto& part : splitList(p.get("segments"))) {
    char* end = nullptr;
    const double v = std::strtod(part.c_str(), &end);
    if (end == part.c_str() || *end != '\0')
      return fail(Status::invalidArgument("--segments: '" + part + "' is not a number"));
    params.segment_lengths_m.push_back(v);
  }
  auto step = p.getInt("step", 1, 100000);
  if (!step) return fail(step.status());
  params.step_frames = *step;
  if (p.get("align") == "se3") {
    params.align = TrajectoryAlignment::kSe3;
  } else if (p.get("align") == "sim3") {
    params.align = TrajectoryAlignment::kSim3;
  } else if (p.get("align") == "none") {
    params.align = TrajectoryAlignment::kNone;
  } else {
    return fail(Status::invalidArgument("--align: unknown alignment '" + p.get("align") +
                                        "' (use se3, sim3 or none)"));
  }
  if (Status s = params.validate(); !s) return fail(s);
  auto max_dt = p.getDouble("max-dt");
  if (!max_dt) return fail(max_dt.status());
  if (*max_dt < 0.0)
    return fail(
        Status::invalidArgument("--max-dt: " + p.get("max-dt") + " is negative (seconds, >= 0)"));

  auto gt = drivers::readTrajectory(p.get("gt"));
  if (!gt) return fail(gt.status());
  auto est = drivers::readTrajectory(p.get("est"));
  if (!est) return fail(est.status());
  if (p.has("body-to-cam") && p.has("euroc"))
    return fail(Status::invalidArgument("--body-to-cam and --euroc both give the camera; use one"));
  if (p.has("body-to-cam") || p.has("euroc")) {
    auto tbs = p.has("euroc") ? drivers::eurocBodyToRectifiedLeft(p.get("euroc"))
                              : drivers::readEurocTbs(p.get("body-to-cam"));
    if (!tbs) return fail(tbs.status());
    for (auto& T : gt->poses) T = T * *tbs;
  }
  std::vector<Eigen::Isometry3d> g, e;
  std::vector<std::size_t> est_index;
  if (Status s = drivers::associateTrajectories(*gt, *est, *max_dt, g, e, &est_index); !s)
    return fail(s);
  std::vector<Eigen::Matrix<double, 6, 6>> covs;
  if (p.has("cov")) {
    auto text = drivers::readTextFile(p.get("cov"));
    if (!text) return fail(text.status());
    std::istringstream lines(*text);
    std::string line;
    std::vector<Eigen::Matrix<double, 6, 6>> all;
    int n = 0;
    while (std::getline(lines, line)) {
      ++n;
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      std::istringstream ls(line);
      Eigen::Matrix<double, 6, 6> P;
      for (int k = 0; k < 36; ++k)
        if (!(ls >> P(k / 6, k % 6)) || !std::isfinite(P(k / 6, k % 6)))
          return fail(Status::corruptData(p.get("cov") + ":" + std::to_string(n) +
                                          ": expected 36 finite numbers"));
      all.push_back(P);
    }
    if (all.size() != est->poses.size())
      return fail(Status::invalidArgument(p.get("cov") + " has " + std::to_string(all.size()) +
                                          " covariances for " + std::to_string(est->poses.size()) +
                                          " estimated poses"));
    for (std::size_t i : est_index) covs.push_back(all[i]);
  }
  auto m = evaluateTrajectory(g, e, params);
  if (!m) return fail(m.status());

  // A length with no segment has no drift: null and the reason, not 0 %.
  std::string segs = "[";
  int segments_found = 0;
  for (std::size_t i = 0; i < m->segments.size(); ++i) {
    const auto& sd = m->segments[i];
    segments_found += sd.count;
    JsonObject js;
    js.add("length_m", sd.length_m, 2).add("count", sd.count);
    if (sd.count > 0) {
      js.add("t_err_pct", sd.t_err_pct).add("r_err_deg_per_m", sd.r_err_deg_per_m, 6);
    } else {
      char why[160];
      if (m->path_length_m < sd.length_m)
        std::snprintf(why, sizeof why, "the ground-truth path (%.2f m) is shorter than %.2f m",
                      m->path_length_m, sd.length_m);
      else
        std::snprintf(
            why, sizeof why,
            "no frames %.2f m apart along the ground truth (segments start every %d frames)",
            sd.length_m, params.step_frames);
      js.addRaw("t_err_pct", "null").addRaw("r_err_deg_per_m", "null").add("reason", why);
    }
    segs += (i ? ", " : "") + js.str();
  }
  segs += "]";
  JsonObject j;
  j.add("frames", m->frames).add("path_length_m", m->path_length_m, 3);
  if (segments_found > 0) {
    j.add("t_err_pct", m->t_err_pct).add("r_err_deg_per_m", m->r_err_deg_per_m, 6);
  } else {
    j.addRaw("t_err_pct", "null")
        .addRaw("r_err_deg_per_m", "null")
        .add("t_err_reason", "no segment of any of the --segments lengths");
  }
  j.addRaw("segments", segs)
      .add("align", p.get("align"))
      .add("ate_rmse_m", m->ate_rmse_m)
      .add("align_scale", m->align_scale, 6)
      .add("rpe_trans_rmse_m", m->rpe_trans_rmse_m)
      .add("rpe_rot_rmse_deg", m->rpe_rot_rmse_deg)
      .add("final_pos_err_m", m->final_pos_err_m)
      .add("final_att_err_deg", m->final_att_err_deg)
      .add("start_rotation_deg", m->start_rotation_deg, 6)
      .addRaw("start_rotation_axis", vec3Json(m->start_rotation_axis))
      .add("ate_after_start_rotation_m", m->ate_after_start_rotation_m)
      .add("final_pos_err_after_start_rotation_m", m->final_pos_err_after_start_rotation_m);
  if (!covs.empty()) {
    auto nees = evaluateNees(g, e, covs);
    if (!nees) return fail(nees.status());
    j.add("nees_frames", nees->frames)
        .add("mean_nees", nees->mean_nees)
        .add("mean_nees_position", nees->mean_nees_position)
        .add("within_2sigma_pct", nees->within_2sigma_pct, 2)
        .add("position_within_2sigma_pct", nees->position_within_2sigma_pct, 2);
  }
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace svslam::cli

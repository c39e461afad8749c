// svslam plot: pictures of a run folder (PNG and SVG): trajectory top view with ground truth and
// 2-sigma ellipses, altitude against time, landmarks, per-stage times.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "drivers/files/run_files.hpp"
#include "drivers/files/trajectory_io.hpp"
#include "eval/plot_scales.hpp"
#include "eval/trajectory_metrics.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "pipeline/run/run_outputs.hpp"
#include "pipeline/tools/plot/plot_figures.hpp"
#include "pipeline/tools/stereo_case.hpp"

namespace svslam::cli {

namespace {

namespace fs = std::filesystem;

Result<Eigen::Vector3d> parseVector3(const std::string& option, const std::string& text) {
  const auto parts = splitList(text);
  Eigen::Vector3d v;
  if (parts.size() != 3)
    return Status::invalidArgument("--" + option + ": expected 3 numbers X,Y,Z, got '" + text +
                                   "'");
  for (int i = 0; i < 3; ++i) {
    char* end = nullptr;
    v[i] = std::strtod(parts[i].c_str(), &end);
    if (end == parts[i].c_str() || *end != '\0' || !std::isfinite(v[i]))
      return Status::invalidArgument("--" + option + ": '" + parts[i] + "' is not a number");
  }
  return v;
}

bool isFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

// Ground truth in the run frame: every ground-truth pose, moved by the transform that aligns
// it to the estimate (se3: Umeyama on the paired positions; none: the first paired poses made
// equal), and their times when they have some.
Status addGroundTruth(const std::string& path, const std::string& align,
                      const drivers::TrajectoryFile& est, plot::RunPlotData& d) {
  auto gt = drivers::readTrajectory(path);
  if (!gt) return gt.status();
  std::vector<Eigen::Isometry3d> g, e;
  std::vector<std::size_t> idx;
  if (Status s = drivers::associateTrajectories(*gt, est, 0.02, g, e, &idx); !s)
    return Status::invalidArgument("ground truth " + path +
                                   " does not pair with the run: " + s.message());
  if (g.empty())
    return Status::invalidArgument("ground truth " + path + ": no pose pairs with the run");
  Eigen::Isometry3d A = e.front() * g.front().inverse();
  if (align == "se3") {
    if (g.size() < 3) return Status::invalidArgument("--align se3 needs 3 paired poses or more");
    std::vector<Eigen::Vector3d> pg, pe;
    for (std::size_t i = 0; i < g.size(); ++i) {
      pg.push_back(g[i].translation());
      pe.push_back(e[i].translation());
    }
    A = umeyamaSe3(pg, pe);  // maps ground truth onto the estimate
  }
  for (const auto& T : gt->poses) d.p_gt.push_back(A * T.translation());
  const double t0 = static_cast<double>(est.t_ns.front()) * 1e-9;
  if (!gt->t_ns.empty()) {
    for (const TimeNs t : gt->t_ns) d.t_gt_s.push_back(static_cast<double>(t) * 1e-9 - t0);
  } else if (gt->poses.size() == est.poses.size()) {
    d.t_gt_s = d.t_s;  // paired by index
  }
  d.gt_label = "ground truth (" + fs::path(path).filename().string() + ", align " + align + ")";
  return Status::ok();
}

}  // namespace

int runPlot(const std::vector<std::string>& args) {
  ArgParser p("plot",
              "Pictures of a `svslam run` output folder, each as PNG and SVG (same drawing):\n"
              "trajectory_top (top view, ground truth, 2-sigma position ellipses),\n"
              "altitude (against time, +/- 2 sigma), landmarks (top view of landmarks.ply),\n"
              "latency (per-stage p50/p99/max of stats.json; histogram of latency.txt when\n"
              "present). Prints JSON listing the files written and what was left out.");
  p.addOption("run", "DIR", "output folder of svslam run", std::nullopt, true);
  p.addOption("out", "DIR", "folder for the pictures (created; default: the run folder)");
  p.addOption("ground-truth", "FILE|none",
              "ground-truth trajectory (KITTI or TUM, same camera; default: the run's "
              "groundtruth_kitti.txt when present)");
  p.addOption("align", "none|se3",
              "ground truth onto the run: none = first poses made equal; se3 = Umeyama", "none");
  p.addOption("gravity", "X,Y,Z",
              "gravity in the run frame (first left camera: x right, y down, z forward), as "
              "map.gravity_in_first_camera: 0,0,1 a down-looking camera, 0,1,0 a car",
              "0,0,1");
  p.addOption("ellipse-every", "N", "a 2-sigma ellipse every N poses (0: about 20)", "0");
  p.addOption("size", "WxH", "picture size in pixels (>= 320x240)", "800x600");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("plot", s); };

  const fs::path run = p.get("run");
  std::error_code ec;
  if (!fs::is_directory(run, ec))
    return fail(Status::notFound("run folder '" + run.string() + "' does not exist"));
  const std::string align = p.get("align");
  if (align != "none" && align != "se3")
    return fail(
        Status::invalidArgument("--align: unknown alignment '" + align + "' (none or se3)"));
  auto gravity = parseVector3("gravity", p.get("gravity"));
  if (!gravity) return fail(gravity.status());
  plot::PlotSettings settings;
  auto frame = horizontalFrame(*gravity);
  if (!frame) return fail(Status::invalidArgument("--gravity: " + frame.status().message()));
  settings.frame = *frame;
  auto every = p.getInt("ellipse-every", 0, 1000000);
  if (!every) return fail(every.status());
  settings.ellipse_every = *every;
  if (Status s = p.getSize("size", settings.width_px, settings.height_px, false); !s)
    return fail(s);
  if (settings.width_px < 320 || settings.height_px < 240)
    return fail(Status::invalidArgument("--size: at least 320x240"));

  plot::RunPlotData d;
  d.run_name = fs::absolute(run).lexically_normal().filename().string();
  if (d.run_name.empty())
    d.run_name = fs::absolute(run).lexically_normal().parent_path().filename().string();
  auto est = drivers::readTrajectory((run / run::files::kTrajectoryTum).string());
  if (!est) return fail(est.status());
  if (est->t_ns.empty())
    return fail(Status::corruptData((run / run::files::kTrajectoryTum).string() +
                                    " has no time stamps (not a TUM file)"));
  for (std::size_t i = 0; i < est->poses.size(); ++i) {
    d.p_est.push_back(est->poses[i].translation());
    d.t_s.push_back(static_cast<double>(est->t_ns[i] - est->t_ns.front()) * 1e-9);
  }
  const fs::path cov_path = run / run::files::kPoseCovariance;
  if (isFile(cov_path)) {
    auto cov = drivers::readPoseCovariances(cov_path.string());
    if (!cov) return fail(cov.status());
    if (cov->size() != est->poses.size())
      return fail(Status::corruptData(cov_path.string() + " has " + std::to_string(cov->size()) +
                                      " covariances for " + std::to_string(est->poses.size()) +
                                      " poses"));
    for (const auto& P : *cov) d.cov_p.push_back(P.block<3, 3>(3, 3));
  }
  std::string gt_path = isFile(run / run::files::kGroundTruthKitti)
                            ? (run / run::files::kGroundTruthKitti).string()
                            : "";
  if (p.has("ground-truth")) gt_path = p.get("ground-truth") == "none" ? "" : p.get("ground-truth");
  if (!gt_path.empty())
    if (Status s = addGroundTruth(gt_path, align, *est, d); !s) return fail(s);

  JsonObject j;
  std::string skipped = "[";
  auto skip = [&](const std::string& why) {
    skipped += (skipped.size() > 1 ? ", " : "") + jsonEscape(why);
  };
  if (d.cov_p.empty()) skip("ellipses: no pose_covariance.txt in the run folder (vo mode)");
  const fs::path ply = run / run::files::kLandmarks;
  if (isFile(ply)) {
    auto l = drivers::readLandmarksPly(ply.string());
    if (!l) return fail(l.status());
    d.landmarks = std::move(*l);
    d.has_landmarks = true;
  } else {
    skip("landmarks: no landmarks.ply in the run folder (vo mode or an older run)");
  }
  const fs::path stats = run / run::files::kStats;
  if (isFile(stats)) {
    auto st = drivers::readStageTimes(stats.string());
    if (!st) return fail(st.status());
    d.stages = std::move(*st);
    d.has_stages = true;
  } else {
    skip("latency: no stats.json in the run folder");
  }
  const fs::path lat = run / run::files::kLatency;
  if (isFile(lat)) {
    auto ms = drivers::readLatencyLog(lat.string());
    if (!ms) return fail(ms.status());
    d.latency_ms = std::move(*ms);
    d.has_latency_log = true;
  }

  int ellipses = 0;
  auto top = plot::trajectoryTopFigure(d, settings, &ellipses);
  if (!top) return fail(top.status());
  std::vector<std::pair<std::string, plot::Figure>> figures;
  figures.emplace_back("trajectory_top", std::move(*top));
  figures.emplace_back("altitude", plot::altitudeFigure(d, settings));
  if (d.has_landmarks) figures.emplace_back("landmarks", plot::landmarksFigure(d, settings));
  if (d.has_stages) figures.emplace_back("latency", plot::latencyFigure(d, settings));

  const fs::path out = p.has("out") ? fs::path(p.get("out")) : run;
  fs::create_directories(out, ec);
  if (!fs::is_directory(out, ec))
    return fail(Status::ioError("cannot create the output folder '" + out.string() + "'"));
  std::string files = "[";
  for (const auto& [name, fig] : figures) {
    const plot::Scene scene = plot::layoutFigure(fig);
    const std::string png = (out / (name + ".png")).string();
    const std::string svg = (out / (name + ".svg")).string();
    if (Status s = drivers::writePlotPng(png, plot::sceneToImage(scene)); !s) return fail(s);
    if (Status s = drivers::writePlotText(svg, plot::sceneToSvg(scene)); !s) return fail(s);
    files += (files.size() > 1 ? ", " : "") + jsonEscape(png) + ", " + jsonEscape(svg);
  }
  files += "]";
  skipped += "]";
  char g[96];
  std::snprintf(g, sizeof g, "[%g, %g, %g]", gravity->x(), gravity->y(), gravity->z());
  j.add("run", run.string())
      .add("poses", static_cast<int>(d.p_est.size()))
      .add("ground_truth", gt_path.empty() ? std::string("none") : gt_path)
      .add("align", align)
      .addRaw("gravity", g)
      .add("top_view_axes", settings.frame.u_name + "," + settings.frame.v_name)
      .add("ellipses", ellipses)
      .add("landmarks", static_cast<int>(d.landmarks.size()))
      .addRaw("files", files)
      .addRaw("skipped", skipped);
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace svslam::cli

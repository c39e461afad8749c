// svslam eval-dem: accuracy and coverage of an elevation map against a ground-truth DEM, or the
// flatness of the map along the path the vehicle drove (the "path strip").
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/files/dem_files.hpp"
#include "drivers/files/trajectory_io.hpp"
#include "eval/dem_metrics.hpp"
#include "map/map_frame.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"

namespace svslam::cli {
namespace {

// "x,y,z": three finite numbers separated by commas; the error names the option.
Status parseVector3(const std::string& option, const std::string& text, std::array<double, 3>& v) {
  std::stringstream in(text);
  std::string part;
  std::size_t n = 0;
  while (std::getline(in, part, ',')) {
    char* end = nullptr;
    const double x = std::strtod(part.c_str(), &end);
    if (n == 3 || part.empty() || *end != '\0' || !std::isfinite(x))
      return Status::invalidArgument("--" + option + ": expected x,y,z, got '" + text + "'");
    v[n++] = x;
  }
  if (n != 3)
    return Status::invalidArgument("--" + option + ": expected x,y,z, got '" + text + "'");
  return Status::ok();
}

int runGroundTruthMode(const ArgParser& p, const map::DemRaster& est) {
  auto fail = [](const Status& s) { return reportFailure("eval-dem", s); };
  auto gt = drivers::readDemGeoTiff(p.get("gt"));
  if (!gt) return fail(gt.status());
  auto s = scoreDem(est, *gt);
  if (!s) return fail(s.status());
  JsonObject j;
  j.add("gt_cells", s->gt_cells)
      .add("est_cells", s->est_cells)
      .add("common_cells", s->common_cells)
      .add("rmse_m", s->rmse_m, 4)
      .add("median_abs_m", s->median_abs_m, 4)
      .add("bias_m", s->bias_m, 4)
      .add("coverage", s->coverage, 4)
      .add("within_2sigma", s->within_2sigma, 4)
      .add("gt_stereo_cells", s->gt_stereo_cells)
      .add("coverage_stereo", s->coverage_stereo, 4);
  std::printf("%s\n", j.str().c_str());
  return 0;
}

int runPathMode(const ArgParser& p, const map::DemRaster& dem) {
  auto fail = [](const Status& s) { return reportFailure("eval-dem", s); };
  std::array<double, 3> g{};
  if (Status st = parseVector3("gravity", p.get("gravity"), g); !st) return fail(st);
  auto half_width = p.getDouble("half-width-m");
  if (!half_width) return fail(half_width.status());
  auto band = p.getDouble("surface-band-m");
  if (!band) return fail(band.status());
  if (!std::isfinite(*band) || *band < 0)
    return fail(Status::invalidArgument("--surface-band-m must be finite and >= 0"));
  auto min_ahead = p.getDouble("min-ahead-m");
  if (!min_ahead) return fail(min_ahead.status());
  if (!std::isfinite(*min_ahead) || *min_ahead < 0)
    return fail(Status::invalidArgument("--min-ahead-m must be finite and >= 0"));
  Eigen::Matrix3d R_map_world;
  if (Status st = map::mapRotationFromGravity(g, R_map_world); !st)
    return fail(Status::invalidArgument("--gravity: " + st.message()));
  auto traj = drivers::readTrajectory(p.get("path"));
  if (!traj) return fail(traj.status());
  // Camera centres: t of T_world_cam (world = first left camera), rotated into the map frame.
  std::vector<Eigen::Vector3d> path_map;
  path_map.reserve(traj->poses.size());
  for (const Eigen::Isometry3d& T_world_cam : traj->poses)
    path_map.push_back(R_map_world * T_world_cam.translation());
  auto s = scorePathStrip(dem, dropPathStart(path_map, *min_ahead), *half_width, *band);
  if (!s) return fail(s.status());
  JsonObject j;
  j.add("strip_cells", s->strip_cells)
      .add("path_length_m", s->path_length_m, 3)
      .add("half_width_m", *half_width, 3)
      .add("height_std_m", s->height_std_m, 4)
      .add("plane_residual_std_m", s->plane_residual_std_m, 4)
      .add("plane_residual_p95_abs_m", s->plane_residual_p95_abs_m, 4)
      .add("median_sigma_m", s->median_sigma_m, 4)
      .add("camera_height_above_plane_m", s->camera_height_above_plane_m, 4)
      .add("surface_band_m", *band, 3)
      .add("surface_cells", s->surface_cells)
      .add("off_surface_cells", s->off_surface_cells)
      .add("surface_residual_std_m", s->surface_residual_std_m, 4);
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace

int runEvalDem(const std::vector<std::string>& args) {
  ArgParser p("eval-dem",
              "Scores an elevation map (dem.tif of svslam run) and prints JSON.\n"
              "With --gt: against a ground-truth DEM of the same cell size. Cells are paired by\n"
              "their map indices (both files in the map frame; geotransforms on the same grid);\n"
              "the observed area is the set of ground-truth cells with a height. Errors are\n"
              "est - gt, metres: rmse_m, median_abs_m, bias_m over common cells; coverage =\n"
              "common / ground-truth cells; within_2sigma = share of common cells with |error|\n"
              "<= 2 sigma of the estimate; coverage_stereo = share of ground-truth cells seen by\n"
              "both cameras (count band > 0) that have an estimate.\n"
              "With --path: flatness of the path strip, the cells with a height whose centre is\n"
              "within --half-width-m (horizontal) of the camera path projected on the map plane:\n"
              "strip_cells, path_length_m, height_std_m, plane_residual_std_m and\n"
              "plane_residual_p95_abs_m (residuals of a least-squares plane z = a x + b y + c),\n"
              "median_sigma_m, camera_height_above_plane_m (mean over the path), metres;\n"
              "the road surface: surface_cells within --surface-band-m of that plane (what\n"
              "stands on the road is not road: off_surface_cells), surface_residual_std_m (RMS\n"
              "of their residuals to a plane refitted to them).\n"
              "Figures over an empty set are null.");
  p.addOption("dem", "FILE", "estimated DEM (GeoTIFF: height_m, sigma_m, count)", std::nullopt,
              true);
  p.addOption("gt", "FILE",
              "ground-truth DEM (GeoTIFF, same 3 bands; count = frames seeing the cell in both "
              "cameras)");
  p.addOption("path", "FILE",
              "trajectory_kitti.txt of the run (left camera poses in the first left camera's "
              "frame): path mode");
  p.addOption("gravity", "X,Y,Z",
              "path mode: gravity in the first left camera's frame, as map.gravity_in_first_camera "
              "of the run",
              "0,0,1");
  p.addOption("half-width-m", "M", "path mode: half-width of the strip, m", "1.0");
  p.addOption("min-ahead-m", "M", "path mode: drop the first M metres of the path", "0");
  p.addOption("surface-band-m", "M",
              "path mode: cells within M of the strip's plane are road surface (0: no surface "
              "figures)",
              "0.3");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("eval-dem", s); };
  const bool has_gt = p.has("gt"), has_path = p.has("path");
  if (has_gt == has_path) {  // a command-line error: exit code 2, as for the parser's
    std::fprintf(stderr, "svslam eval-dem: %s\n",
                 has_gt ? "give either --gt or --path, not both" : "give --gt FILE or --path FILE");
    return 2;
  }

  auto dem = drivers::readDemGeoTiff(p.get("dem"));
  if (!dem) return fail(dem.status());
  return has_gt ? runGroundTruthMode(p, *dem) : runPathMode(p, *dem);
}

}  // namespace svslam::cli

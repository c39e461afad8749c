// svslam eval-dem: accuracy and coverage of an elevation map against a ground-truth DEM.
#include <cstdio>
#include <string>
#include <vector>

#include "drivers/files/dem_files.hpp"
#include "eval/dem_metrics.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"

namespace svslam::cli {

int runEvalDem(const std::vector<std::string>& args) {
  ArgParser p("eval-dem",
              "Scores an elevation map (dem.tif of svslam run) against a ground-truth DEM of the\n"
              "same cell size and prints JSON. Cells are paired by their map indices (both files\n"
              "in the map frame; geotransforms on the same grid); the observed area is the set of\n"
              "ground-truth cells with a height. Errors are est - gt, metres: rmse_m,\n"
              "median_abs_m, bias_m over common cells; coverage = common / ground-truth cells;\n"
              "within_2sigma = share of common cells with |error| <= 2 sigma of the estimate;\n"
              "coverage_stereo = share of ground-truth cells seen by both cameras (count band\n"
              "> 0) that have an estimate. Shares over an empty set are null.");
  p.addOption("dem", "FILE", "estimated DEM (GeoTIFF: height_m, sigma_m, count)", std::nullopt,
              true);
  p.addOption("gt", "FILE",
              "ground-truth DEM (GeoTIFF, same 3 bands; count = frames seeing the cell in both "
              "cameras)",
              std::nullopt, true);
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("eval-dem", s); };

  auto est = drivers::readDemGeoTiff(p.get("dem"));
  if (!est) return fail(est.status());
  auto gt = drivers::readDemGeoTiff(p.get("gt"));
  if (!gt) return fail(gt.status());
  auto s = scoreDem(*est, *gt);
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

}  // namespace svslam::cli

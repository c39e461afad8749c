// svslam eval-disparity: scores disparity maps against ground truth (Middlebury, KITTI, files).
#include <cstdio>
#include <string>
#include <vector>

#include "drivers/files/image_io.hpp"
#include "drivers/datasets/stereo_datasets.hpp"
#include "eval/disparity_metrics.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/tools/disparity_output.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "pipeline/tools/stereo_case.hpp"
#include "pipeline/tools/stereo_options.hpp"
#include "pipeline/thread_pool_executor.hpp"

namespace svslam::cli {
namespace {

std::string metricsFields(const DisparityMetrics& m) {
  // toJson gives "{...}"; strip the braces to merge its fields into a larger object.
  const std::string j = toJson(m);
  return j.substr(1, j.size() - 2);
}

}  // namespace

int runEvalDisparity(const std::vector<std::string>& args) {
  ArgParser p(
      "eval-disparity",
      "Scores a disparity map against ground truth: bad>0.5/1/2/3 px among valid pixels and\n"
      "with invalid pixels counted as bad, density, mean absolute error. The map is read\n"
      "from --disp, or computed with the stereo options below from the case's images.\n"
      "Cases: --dataset DIR[,DIR...] recognises Middlebury v2 (imL/imR/groundtruth/info.txt),\n"
      "Middlebury 2006 (*L, *R, *GT.png) and KITTI stereo (image_0, image_1, disp_noc)\n"
      "folders; or give --gt (and --left/--right to compute) explicitly. With several\n"
      "datasets the JSON holds one entry per case and the means.");
  p.addOption("dataset", "DIR[,DIR...]", "ground-truth case folder(s)");
  p.addOption("mask-kind", "nonocc|all|disc", "which mask of the dataset to evaluate on", "nonocc");
  p.addOption("frame", "NAME", "KITTI frame file name (default: the first in image_0)");
  p.addOption("gt", "FILE", "ground-truth disparity (.png scaled by --gt-scale, or .pfm)");
  p.addOption("gt-scale", "S", "ground truth value per pixel of disparity (.png)", "1");
  p.addOption("mask", "FILE", "evaluation mask (255 = evaluate)");
  p.addOption("left", "FILE", "left image (to compute the disparity with --gt)");
  p.addOption("right", "FILE", "right image (to compute the disparity with --gt)");
  p.addOption("disp", "FILE",
              "disparity to score instead of computing one (.pfm, or .png / --disp-scale)");
  p.addOption("disp-scale", "S", "value per pixel of disparity of a .png --disp", "256");
  p.addOption("max-disp", "N", "one past the largest disparity searched (default: the case's)");
  addStereoOptions(p);
  p.addOption("out", "FILE", "write the computed disparity (.pfm or .png; single case only)");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("eval-disparity", s); };

  // Which cases.
  std::vector<drivers::StereoGtCase> cases;
  if (p.has("dataset")) {
    for (const auto& dir : splitList(p.get("dataset"))) {
      auto c = drivers::findStereoGtCase(dir, p.get("mask-kind"), p.has("frame") ? p.get("frame") : "");
      if (!c) return fail(c.status());
      cases.push_back(*c);
    }
    if (cases.empty()) return fail(Status::invalidArgument("--dataset lists no folder"));
  } else if (p.has("gt")) {
    auto scale = p.getDouble("gt-scale");
    if (!scale) return fail(scale.status());
    drivers::StereoGtCase c;
    c.name = p.get("gt");
    c.gt = p.get("gt");
    c.gt_scale = *scale;
    c.mask = p.has("mask") ? p.get("mask") : "";
    c.left = p.has("left") ? p.get("left") : "";
    c.right = p.has("right") ? p.get("right") : "";
    c.max_disp = 0;
    cases.push_back(c);
  } else {
    return fail(Status::invalidArgument("give --dataset DIR or --gt FILE (see --help)"));
  }
  const bool given = p.has("disp");
  if (given && cases.size() != 1)
    return fail(Status::invalidArgument("--disp scores exactly one case"));
  if (p.has("out") && cases.size() != 1)
    return fail(Status::invalidArgument("--out needs exactly one case"));
  if (p.has("out")) {
    if (Status s = checkOutputPath(p.get("out"), "out"); !s) return fail(s);
  }
  int max_disp = 0;
  if (p.has("max-disp")) {
    auto m = p.getInt("max-disp", 1, 100000);
    if (!m) return fail(m.status());
    max_disp = *m;
  }
  if (!given) {
    for (const auto& c : cases) {
      if (c.left.empty() || c.right.empty())
        return fail(Status::invalidArgument(
            "to compute a disparity give --left and --right (or --disp to score a file)"));
      if (max_disp <= 0 && c.max_disp <= 0)
        return fail(Status::invalidArgument("--max-disp is needed for " + c.name));
    }
  }
  auto params = stereoParamsFromArgs(p, max_disp > 0 ? max_disp : 64);
  if (!params) return fail(params.status());
  auto threads = p.getInt("threads", 1, 64);
  if (!threads) return fail(threads.status());
  ThreadPoolExecutor executor(*threads);

  std::vector<std::string> entries;
  double sum_bad1 = 0, sum_bad2 = 0, sum_bad3 = 0, sum_bad05 = 0, sum_density = 0, sum_bad1_all = 0,
         sum_mae = 0;
  for (const auto& info : cases) {
    auto loaded = loadCase(info, !given, p.get("mask-kind") == "nonocc");
    if (!loaded) return fail(loaded.status());
    ImageF32 est;
    double ms = 0;
    if (given) {
      const std::string d = p.get("disp");
      auto ds = p.getDouble("disp-scale");
      if (!ds) return fail(ds.status());
      auto e = drivers::loadDisparity(d, *ds);
      if (!e) return fail(e.status());
      est = std::move(e).value();
    } else {
      DenseStereoParams sp = *params;
      sp.max_disp = max_disp > 0 ? max_disp : info.max_disp;
      DisparityResult r;
      if (Status s = computeDisparity(*loaded, sp, executor, r, &ms); !s)
        return fail(Status(s.code(), info.name + ": " + s.message()));
      if (p.has("out")) {
        if (Status s = writeDisparityOutputs(r, p.get("out"), "", "", sp.max_disp); !s)
          return fail(s);
      }
      est = std::move(r.disparity_px);
    }
    auto m = evaluateDisparity(est.cview(), loaded->gt.cview(), loaded->mask.cview());
    if (!m) return fail(Status(m.status().code(), info.name + ": " + m.status().message()));
    JsonObject j;
    j.add("case", info.name)
        .add("mask",
             !info.mask.empty()
                 ? info.mask
                 : (p.get("mask-kind") == "nonocc" ? "nonocc derived from ground truth" : "none"));
    if (!given) j.add("max_disp", max_disp > 0 ? max_disp : info.max_disp).add("compute_ms", ms, 3);
    std::string e = j.str();
    e = e.substr(0, e.size() - 1) + ", " + metricsFields(*m) + "}";
    entries.push_back(e);
    sum_bad05 += m->bad05_valid_pct;
    sum_bad1 += m->bad1_valid_pct;
    sum_bad2 += m->bad2_valid_pct;
    sum_bad3 += m->bad3_valid_pct;
    sum_bad1_all += m->bad1_all_pct;
    sum_density += m->density_pct;
    sum_mae += m->mae_valid_px;
  }
  if (entries.size() == 1) {
    std::printf("%s\n", entries[0].c_str());
    return 0;
  }
  std::string arr = "[";
  for (std::size_t i = 0; i < entries.size(); ++i) arr += (i ? ", " : "") + entries[i];
  arr += "]";
  const double n = static_cast<double>(entries.size());
  JsonObject out;
  out.add("method", toString(params->cost))
      .add("mean_bad05_valid_pct", sum_bad05 / n)
      .add("mean_bad1_valid_pct", sum_bad1 / n)
      .add("mean_bad2_valid_pct", sum_bad2 / n)
      .add("mean_bad3_valid_pct", sum_bad3 / n)
      .add("mean_bad1_all_pct", sum_bad1_all / n)
      .add("mean_density_pct", sum_density / n)
      .add("mean_mae_valid_px", sum_mae / n)
      .addRaw("cases", arr);
  std::printf("%s\n", out.str().c_str());
  return 0;
}

}  // namespace svslam::cli

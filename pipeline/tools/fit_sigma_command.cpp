// svslam fit-sigma: calibrates the curvature -> sigma_d model of the dense stereo (or, with
// --matcher points, of the sparse ZNCC matches of the corners) on ground truth and checks it on
// held-apart cases.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "pipeline/tools/point_sigma_samples.hpp"
#include "pipeline/tools/stereo_case.hpp"
#include "pipeline/tools/stereo_options.hpp"
#include "pipeline/thread_pool_executor.hpp"
#include "stereo/sigma_model.hpp"

namespace svslam::cli {
namespace {

// Appends (kappa, |d - gt|) of every valid, evaluated pixel of one case.
// At most max_per_case samples are kept per case (an even, deterministic subsampling), so that
// one large image does not decide the fit alone.
Status collectSamples(const std::string& dir, const std::string& mask_kind,
                      const DenseStereoParams& params, Executor& ex, std::size_t max_per_case,
                      std::vector<float>& kappa, std::vector<float>& err) {
  auto info = drivers::findStereoGtCase(dir, mask_kind, "");
  if (!info) return info.status();
  auto c = loadCase(*info, true, mask_kind == "nonocc");
  if (!c) return c.status();
  DisparityResult r;
  DenseStereoParams sp = params;
  sp.max_disp = info->max_disp;
  if (Status s = computeDisparity(*c, sp, ex, r, nullptr); !s)
    return Status(s.code(), info->name + ": " + s.message());
  std::vector<float> k_case, e_case;
  for (int y = 0; y < c->gt.height(); ++y)
    for (int x = 0; x < c->gt.width(); ++x) {
      const float g = c->gt(x, y);
      const float d = r.disparity_px(x, y);
      if (!std::isfinite(g) || !(g > 0.0f) || !std::isfinite(d)) continue;
      if (!c->mask.empty() && c->mask(x, y) == 0) continue;
      k_case.push_back(r.curvature(x, y));
      e_case.push_back(std::abs(d - g));
    }
  const std::size_t n = k_case.size();
  const std::size_t keep = std::min(n, max_per_case);
  for (std::size_t j = 0; j < keep; ++j) {
    const std::size_t idx = j * n / keep;
    kappa.push_back(k_case[idx]);
    err.push_back(e_case[idx]);
  }
  return Status::ok();
}

// Appends (kappa, |d - gt|) of every sparse match with ground truth of one case (the corner
// detector and the point matcher at their default parameters, as `svslam run` uses them).
Status collectPointCase(const std::string& dir, const std::string& mask_kind,
                        std::vector<float>& kappa, std::vector<float>& err) {
  auto info = drivers::findStereoGtCase(dir, mask_kind, "");
  if (!info) return info.status();
  auto c = loadCase(*info, true, mask_kind == "nonocc");
  if (!c) return c.status();
  return collectPointSamples(*c, CornerParams{}, StereoMatchParams{}, kappa, err);
}

}  // namespace

int runFitSigma(const std::vector<std::string>& args) {
  ArgParser p(
      "fit-sigma",
      "Fits the table kappa -> sigma_d (seed 001 fig. 3) on ground-truth cases: pixels are\n"
      "grouped by peak curvature kappa into equal-count bins and sigma is the 68.27th\n"
      "percentile of |d - d_true| in each bin (made non-increasing). Reports the share of\n"
      "errors inside one sigma on the training cases and on held-apart cases.\n"
      "--matcher points fits the table of the sparse matches instead: corners (default\n"
      "detector) matched by ZNCC along the row, kappa = 2 s(d) - s(d-1) - s(d+1) of the\n"
      "score peak, every match with ground truth a sample (the stereo options are unused).");
  p.addOption("train", "DIR[,DIR...]", "ground-truth case folders to fit on", std::nullopt, true);
  p.addOption("holdout", "DIR[,DIR...]", "held-apart case folders to check the fit on");
  p.addOption("matcher", "dense|points", "whose sigma to fit: dense census stereo or sparse ZNCC "
              "matches of corners", "dense");
  p.addOption("mask-kind", "nonocc|all|disc", "evaluation mask of the cases", "nonocc");
  p.addOption("bins", "N", "number of curvature bins (2..200)", "16");
  p.addOption("samples-per-case", "N",
              "at most N pixels per case, evenly subsampled (1000..10000000)", "100000");
  p.addOption("out", "FILE", "write the model (lines 'kappa sigma_px'), usable with --sigma-model");
  addStereoOptions(p);
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("fit-sigma", s); };
  auto bins = p.getInt("bins", 2, 200);
  if (!bins) return fail(bins.status());
  auto per_case = p.getInt("samples-per-case", 1000, 10000000);
  if (!per_case) return fail(per_case.status());
  const auto cap = static_cast<std::size_t>(*per_case);
  auto params = stereoParamsFromArgs(p, 64);
  if (!params) return fail(params.status());
  auto threads = p.getInt("threads", 1, 64);
  if (!threads) return fail(threads.status());
  ThreadPoolExecutor ex(*threads);

  const std::string matcher = p.get("matcher");
  if (matcher != "dense" && matcher != "points")
    return fail(Status::invalidArgument("--matcher must be dense or points"));
  auto collect = [&](const std::string& dir, std::vector<float>& k, std::vector<float>& e) {
    if (matcher == "points") return collectPointCase(dir, p.get("mask-kind"), k, e);
    return collectSamples(dir, p.get("mask-kind"), *params, ex, cap, k, e);
  };
  std::vector<float> k_train, e_train, k_hold, e_hold;
  for (const auto& dir : splitList(p.get("train")))
    if (Status s = collect(dir, k_train, e_train); !s) return fail(s);
  if (p.has("holdout"))
    for (const auto& dir : splitList(p.get("holdout")))
      if (Status s = collect(dir, k_hold, e_hold); !s) return fail(s);
  auto model = fitSigmaModel(k_train, e_train, *bins);
  if (!model) return fail(model.status());
  if (p.has("out")) {
    const std::string path = p.get("out");
    const std::string tmp = path + ".tmp";
    {
      std::ofstream f(tmp);
      if (!f) return fail(Status::ioError("cannot write " + path));
      if (matcher == "points")
        f << "# svslam sigma model: kappa (ZNCC / px^2) sigma_d (px); sparse ZNCC matches\n";
      else
        f << "# svslam sigma model: kappa (cost units / px / px^2) sigma_d (px); method "
          << toString(params->cost) << ", window " << params->window_w << "x"
          << params->window_h << "\n";
      char line[64];
      for (std::size_t i = 0; i < model->curvature.size(); ++i) {
        std::snprintf(line, sizeof line, "%.6g %.6g\n", model->curvature[i], model->sigma_px[i]);
        f << line;
      }
      if (!f) return fail(Status::ioError("cannot write " + path));
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
      std::remove(tmp.c_str());
      return fail(Status::ioError("cannot rename " + tmp + " to " + path));
    }
  }
  std::string knots = "[";
  for (std::size_t i = 0; i < model->curvature.size(); ++i) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s[%.6g, %.6g]", i ? ", " : "", model->curvature[i],
                  model->sigma_px[i]);
    knots += buf;
  }
  knots += "]";
  JsonObject j;
  j.add("train_samples", static_cast<std::int64_t>(k_train.size()))
      .add("train_coverage_1sigma", sigmaCoverage(*model, k_train, e_train))
      .add("holdout_samples", static_cast<std::int64_t>(k_hold.size()))
      .add("holdout_coverage_1sigma", k_hold.empty() ? NAN : sigmaCoverage(*model, k_hold, e_hold))
      .addRaw("knots_kappa_sigma", knots);
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace svslam::cli

// svslam disparity: dense disparity of one rectified pair, timed, written to files.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "drivers/files/image_io.hpp"
#include "drivers/synthetic/synthetic_pair.hpp"
#include "eval/disparity_metrics.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/tools/disparity_output.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "pipeline/tools/stereo_options.hpp"
#include "pipeline/thread_pool_executor.hpp"

namespace svslam::cli {

int runDisparity(const std::vector<std::string>& args) {
  ArgParser p("disparity",
              "Computes the dense disparity of a rectified pair by census or SAD correlation with\n"
              "reverse correlation, sub-pixel refinement and a per-pixel sigma_d. Prints one JSON\n"
              "object: size, method, threads, median_ms of the computation alone, valid_fraction.");
  p.addOption("left", "FILE",
              "left image (grey or colour, converted to grey); without --left and\n"
              "                            --right the built-in synthetic pair (slanted plane + "
              "box, exact\n"
              "                            ground truth) is used and scored");
  p.addOption("right", "FILE", "right image, same size as the left");
  p.addOption("max-disp", "N",
              "one past the largest disparity searched, px (0 < N < width); required\n"
              "                            with images, 64 for the synthetic pair");
  p.addOption("synthetic-size", "WxH", "size of the built-in synthetic pair", "640x480");
  p.addOption("seed", "N", "seed of the built-in synthetic pair's texture", "1");
  addStereoOptions(p);
  p.addOption("repeat", "K", "compute K times and report the median time (1..1000)", "1");
  p.addOption("out", "FILE",
              "disparity output: .pfm (float, +inf invalid) or .png (uint16 = d*256, 0 invalid)");
  p.addOption("sigma", "FILE.pfm", "write sigma_d (px) as PFM, +inf where invalid");
  p.addOption("color", "FILE.png", "write a colour-mapped disparity picture");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("disparity", s); };
  const bool synthetic = !p.has("left") && !p.has("right");
  if (!synthetic && (!p.has("left") || !p.has("right")))
    return fail(Status::invalidArgument(
        "give both --left and --right (or neither, for the built-in synthetic pair)"));
  if (!synthetic && !p.has("max-disp"))
    return fail(Status::invalidArgument("--max-disp is required with images"));
  Result<int> max_disp = 64;
  if (p.has("max-disp")) max_disp = p.getInt("max-disp", -1000000, 1000000);
  if (!max_disp) return fail(max_disp.status());
  if (*max_disp <= 0) return fail(Status::invalidArgument("--max-disp must be > 0"));
  auto repeat = p.getInt("repeat", 1, 1000);
  if (!repeat) return fail(repeat.status());
  auto threads = p.getInt("threads", 1, 64);
  if (!threads) return fail(threads.status());
  for (const char* key : {"out", "sigma", "color"}) {
    if (!p.has(key)) continue;
    if (Status s = checkOutputPath(p.get(key), key); !s) return fail(s);
  }
  auto params = stereoParamsFromArgs(p, *max_disp);
  if (!params) return fail(params.status());

  Result<ImageU8> left = ImageU8(), right = ImageU8();
  std::optional<drivers::SyntheticPair> truth;
  if (synthetic) {
    drivers::SyntheticPairParams sp;
    if (Status s = p.getSize("synthetic-size", sp.width, sp.height, false); !s) return fail(s);
    auto seed = p.getInt("seed", 0, 1 << 30);
    if (!seed) return fail(seed.status());
    sp.seed = static_cast<std::uint32_t>(*seed);
    auto pair = drivers::makeSyntheticPair(sp);
    if (!pair) return fail(pair.status());
    left = std::move(pair->left);
    right = std::move(pair->right);
    truth = std::move(pair).value();
  } else {
    left = drivers::loadGrey(p.get("left"));
    if (!left) return fail(left.status());
    right = drivers::loadGrey(p.get("right"));
    if (!right) return fail(right.status());
  }
  if (left->width() != right->width() || left->height() != right->height())
    return fail(Status::invalidArgument(
        "left and right images differ in size: " + std::to_string(left->width()) + "x" +
        std::to_string(left->height()) + " vs " + std::to_string(right->width()) + "x" +
        std::to_string(right->height())));

  DenseStereo stereo(*params, left->width(), left->height());
  if (!stereo.initStatus()) return fail(stereo.initStatus());
  ThreadPoolExecutor executor(*threads);
  DisparityResult result;
  std::vector<double> times_ms;
  for (int k = 0; k < *repeat; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    Status s = stereo.process(left->cview(), right->cview(), result, executor);
    const auto t1 = std::chrono::steady_clock::now();
    if (!s) return fail(s);
    times_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  std::sort(times_ms.begin(), times_ms.end());
  const double median_ms = times_ms[times_ms.size() / 2];

  if (Status s = writeDisparityOutputs(result, p.has("out") ? p.get("out") : "",
                                       p.has("sigma") ? p.get("sigma") : "",
                                       p.has("color") ? p.get("color") : "", *max_disp);
      !s)
    return fail(s);

  const double n = static_cast<double>(left->width()) * left->height();
  JsonObject j;
  j.add("width", left->width())
      .add("height", left->height())
      .add("method", toString(params->cost))
      .add("min_disp", params->min_disp)
      .add("max_disp", params->max_disp)
      .add("threads", *threads)
      .add("stripes", params->num_stripes)
      .add("backend", result.stats.backend)
      .add("repeat", *repeat)
      .add("median_ms", median_ms, 3)
      .add("min_ms", times_ms.front(), 3)
      .add("valid_fraction", result.stats.valid / n, 4)
      .add("rejected_no_candidate", result.stats.no_candidate)
      .add("rejected_low_texture", result.stats.low_texture)
      .add("rejected_not_unique", result.stats.not_unique)
      .add("rejected_lr_check", result.stats.lr_inconsistent);
  if (truth) {
    j.add("source", "synthetic");
    auto m = evaluateDisparity(result.disparity_px.cview(), truth->gt_disparity_px.cview(),
                               truth->nonocc_mask.cview());
    if (m) {
      j.add("synthetic_bad1_valid_pct", m->bad1_valid_pct)
          .add("synthetic_density_pct", m->density_pct)
          .add("synthetic_mae_valid_px", m->mae_valid_px);
    }
  }
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace svslam::cli

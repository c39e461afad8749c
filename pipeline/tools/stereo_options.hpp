#pragma once
// The dense-stereo options shared by `svslam disparity` and `svslam eval-disparity`.
#include "pipeline/cli/arg_parser.hpp"
#include "stereo/dense_stereo.hpp"

namespace svslam::cli {

// Declares --min-disp, --method, --window, --census, --prefilter, --prefilter-cap,
// --prefilter-size,
// --uniqueness, --texture, --no-lr-check, --lr-max-diff, --no-subpixel, --backend, --threads,
// --stripes, --sigma-model. (--max-disp is declared by each command.)
void addStereoOptions(ArgParser& p);

// Builds and validates the parameters from parsed options; max_disp comes from the caller.
Result<DenseStereoParams> stereoParamsFromArgs(const ArgParser& p, int max_disp);

// Parses a sigma-model file: lines "kappa sigma_px" (# comments allowed).
Result<SigmaModel> loadSigmaModel(const std::string& path);

}  // namespace svslam::cli

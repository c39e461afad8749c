#pragma once
// Dense disparity accuracy against ground truth, the usual way (Middlebury / KITTI style).
//
// Disparities are in pixels, d = x_left - x_right, for the left view. An estimate is "returned"
// (valid) when it is finite; invalid estimates are +inf by the library's convention (NaN and
// -inf are treated the same way). Ground truth is known where it is finite and > 0.
//
//   evaluated E = { p : gt(p) finite, gt(p) > 0, and (mask empty or mask(p) != 0) }
//   valid     V = { p in E : est(p) finite }
//   density_pct      = 100 |V| / |E|
//   badN_valid_pct   = 100 |{ p in V : |est(p) - gt(p)| > N }| / |V|          (strict >)
//   badN_all_pct     = 100 (|E \ V| + |{ p in V : |est(p) - gt(p)| > N }|) / |E|
//   mae_valid_px     = mean over V of |est - gt|, rmse_valid_px = sqrt(mean over V of (est - gt)^2)
// with N in {0.5, 1, 2, 3} px. When V is empty the "valid" statistics are 0 (never NaN) and every
// badN_all_pct is 100. Pure computation: no I/O.
#include <cstdint>
#include <string>

#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam {

struct DisparityMetrics {
  std::int64_t evaluated = 0;  // pixels with known ground truth inside the mask
  std::int64_t valid = 0;      // evaluated pixels where the estimate is finite
  double density_pct = 0;      // 100 * valid / evaluated, 0..100
  // Share of valid pixels whose absolute error exceeds 0.5, 1, 2, 3 px; 0..100.
  double bad05_valid_pct = 0;
  double bad1_valid_pct = 0;
  double bad2_valid_pct = 0;
  double bad3_valid_pct = 0;
  // Share of evaluated pixels that are invalid or exceed the threshold; 0..100.
  double bad05_all_pct = 0;
  double bad1_all_pct = 0;
  double bad2_all_pct = 0;
  double bad3_all_pct = 0;
  double mae_valid_px = 0;   // mean absolute error over valid pixels, px
  double rmse_valid_px = 0;  // root mean square error over valid pixels, px
};

// est, gt: same size. mask: empty (evaluate everywhere the ground truth is known) or the same
// size as gt, nonzero = evaluate. Errors (invalidArgument): empty est or gt, size mismatch
// (the message names both sizes), no evaluated pixel at all.
Result<DisparityMetrics> evaluateDisparity(ImageView<const float> est, ImageView<const float> gt,
                                           ImageView<const std::uint8_t> mask);

// One flat JSON object with the field names above, e.g.
// {"evaluated": 1234, "valid": 1200, "density_pct": 97.2447, ...}. Counts are integers, every
// other field has exactly 4 decimals (locale independent); a non-finite value prints as null,
// never as nan or inf.
std::string toJson(const DisparityMetrics& m);

}  // namespace svslam

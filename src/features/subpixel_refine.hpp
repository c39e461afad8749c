#pragma once
// Iterative sub-pixel refinement of a patch match (Lucas-Kanade / Gauss-Newton), to replace the
// parabola through three correlation scores where an unbiased position matters.
//
// Why: the parabola fitted to ZNCC (or SSD) scores at integer shifts is biased towards integer
// positions ("pixel locking"): on the synthetic flight its disparity error is -0.04 px at
// fractional parts 0.2 and +0.04 px at 0.7 for an rms of 0.06 px (docs/slam.md). The bias does
// not average out along a track (the fraction changes slowly), so the filter sees it as drift.
//
// Both refinements are Gauss-Newton on a zero-mean, unit-norm patch difference (so a gain and an
// offset between the images do not bias the shift), with the Jacobian taken from the fixed
// template (the forward-additive step with the template's gradient: one gradient and one
// Hessian per call, each iteration only resamples the image):
//
//  - refineDisparity (rectified pair, same row): template T = the left patch at integer (x, y),
//    its x gradient by the 5-tap derivative (-1, 8, 0, -8, 1) / 12 (read from the image beyond
//    the patch); the right image R is resampled at (x + i - d, y + j), and
//      d <- d - sum g (Tn - Rn) / sum g^2   (n: normalised, g = T_x / |T - mean T|);
//  - refineTranslation (a template T, e.g. a landmark's warped patch, in an image I): over the
//    template's interior (offsets within h - 1, where central differences exist), I resampled at
//    (u + i, v + j), (u, v) <- (u, v) + H^-1 sum grad Tn (Tn - In), H = sum grad Tn grad Tn^T.
//
// The fixed point is the position where the resampled patch equals the template, whatever the
// gradient's accuracy (which sets the convergence rate only). The resampling is Lanczos-4
// corrected to reproduce linear ramps: its phase error, which would bias the shift, is under
// 0.006 px at every frequency up to 2 rad/px (linear and Keys cubic interpolation shift by 0.03 px
// too little at 1.3 rad/px). The result is accepted when the iterations converge (|step| <
// stop_px) within max_shift_px of the start and neither patch is flat; otherwise the functions
// return false, leave their outputs untouched, and the caller keeps its parabola estimate.
// Pure arithmetic on the given views: no allocation.
#include <cstdint>

#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam {

struct SubpixelRefineParams {
  int max_iterations = 10;    // Gauss-Newton iterations, 1..50
  double stop_px = 0.005;     // converged when the shift step is below this, px, > 0
  double max_shift_px = 1.0;  // largest distance from the start, px, (0, 3]
  Status validate() const;
};

// Disparity of the left patch at integer (x, y), half size h (1..15), in the right image,
// starting from the disparity d_start.
bool refineDisparity(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right, int x,
                     int y, int h, double d_start, const SubpixelRefineParams& params,
                     double& d_px);

// Position (u, v) of the centre of the square template `tmpl` (side 2 h + 1, row-major, stride
// 2 h + 1, h in 2..15) in `image`, starting from (u_start, v_start).
bool refineTranslation(const std::uint8_t* tmpl, int h, ImageView<const std::uint8_t> image,
                       double u_start, double v_start, const SubpixelRefineParams& params,
                       double& u_px, double& v_px);

}  // namespace svslam

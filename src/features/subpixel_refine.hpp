#pragma once
// Iterative sub-pixel refinement of a patch match (Lucas-Kanade / Gauss-Newton), to replace the
// parabola through three correlation scores where an unbiased position matters.
//
// Why: the parabola fitted to ZNCC (or SSD) scores at integer shifts is biased towards integer
// positions ("pixel locking"): on the synthetic flight its disparity error is -0.04 px at
// fractional parts 0.2 and +0.04 px at 0.7 for an rms of 0.06 px (docs/slam.md). The bias does
// not average out along a track (the fraction changes slowly), so the filter sees it as drift.
//
// Both refinements minimise a sum of squared differences with an affine photometric model
// (gain a, offset b, so exposure differences between the cameras or the frames do not bias the
// shift), over the (2h + 1)^2 pixels of the patch, by Gauss-Newton from a start (typically the
// parabola's estimate):
//
//  - refineDisparity (rectified pair, same row): with d = d0 + e, d0 the integer nearest the
//    start,
//      r_i(e, a, b) = a L(x_i + e/2, y_i) + b - R(x_i - d0 - e/2, y_i),
//    both images sampled by linear interpolation at the same fractional offset |e/2| (symmetric
//    sampling: the interpolation smooths both sides alike, so it biases neither), the left point
//    moves by e/2 <= 0.5 px (the disparity gradient on a patch is negligible). The x gradients
//    are central differences of the interpolated rows; J = [(a L_x + R_x) / 2, L, 1].
//  - refineTranslation (a template T, e.g. a landmark's warped patch, in an image I):
//      r_ij(u, v, a, b) = a T(i, j) + b - I(u + i, v + j),
//    I sampled bilinearly, J = [-I_x, -I_y, T, 1].
// Each step solves the normal equations J^T J dp = -J^T r (LDLT). The result is accepted when
// the iterations converge (|step| < stop_px) within max_shift_px of the start and the patch is
// not flat; otherwise the functions return false and the caller keeps its parabola estimate.
// Pure arithmetic on the given views: no allocation.
#include <cstdint>

#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam {

struct SubpixelRefineParams {
  int max_iterations = 10;    // Gauss-Newton iterations, 1..50
  double stop_px = 0.002;     // converged when the shift step is below this, px, > 0
  double max_shift_px = 1.0;  // largest distance from the start, px, (0, 3]
  Status validate() const;
};

// Disparity of the left patch at integer (x, y), half size h, in the right image, starting from
// the disparity d_start. On success d_px = d0 + e and u_px = x + e / 2 (the left position the
// disparity belongs to); on failure the outputs are untouched.
bool refineDisparity(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                     int x, int y, int h, double d_start, const SubpixelRefineParams& params,
                     double& d_px, double& u_px);

// Position (u, v) of the centre of the square template `tmpl` (side 2 h + 1, row-major, stride
// 2 h + 1) in `image`, starting from (u_start, v_start); on failure the outputs are untouched.
bool refineTranslation(const std::uint8_t* tmpl, int h, ImageView<const std::uint8_t> image,
                       double u_start, double v_start, const SubpixelRefineParams& params,
                       double& u_px, double& v_px);

}  // namespace svslam

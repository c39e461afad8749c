#pragma once
// Ground-truth samples for the sigma model of the sparse stereo matches: the corners of a case's
// left image (CornerDetector) matched along the row (StereoPointMatcher), each match giving its
// ZNCC peak curvature kappa = 2 s(d) - s(d-1) - s(d+1) and its error |d - d_true| (px) at the
// pixel the disparity was measured at (the nearest pixel of the corner). Shared by
// `svslam fit-sigma --matcher points` and tests/features/point_sigma_calibration_test.
#include <vector>

#include "core/status.hpp"
#include "features/corner_detector.hpp"
#include "features/stereo_point_matcher.hpp"
#include "pipeline/tools/stereo_case.hpp"

namespace svslam::cli {

// Appends (kappa, |d - d_true|) of every match whose pixel has ground truth (> 0, finite) and
// is inside the case's mask. `match.max_disp_px` is replaced by the case's max_disp + 1 (a peak
// at the last searchable disparity is then not on the border of the range). `matches`
// (optional) receives the number of matches before the ground-truth filter.
Status collectPointSamples(const LoadedCase& c, const CornerParams& corners,
                           StereoMatchParams match, std::vector<float>& kappa,
                           std::vector<float>& abs_err, int* matches = nullptr);

}  // namespace svslam::cli

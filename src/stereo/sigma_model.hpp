#pragma once
// SigmaModel: the calibrated mapping from the curvature of the matching-cost curve at its
// minimum to the standard deviation of the disparity (seed 001 sec 4.1 and fig. 3: "the
// sharper the peak, the more precise the disparity").
//
// Curvature is measured on the aggregated cost with the parabola through (d-1, c-), (d, c0),
// (d+1, c+):  kappa = (c- + c+ - 2 c0) / A, with A the aggregation-window area in pixels, so
// kappa is in cost units per pixel per px^2 and comparable across window sizes.
// The model is a piecewise-linear table (kappa_i, sigma_i), kappa strictly increasing, sigma
// non-increasing; kappa below the first knot gives sigma_0, above the last gives the last sigma.
// The table is fitted on ground truth (svslam fit-sigma; tests/stereo/sigma_calibration_test)
// so that about 68 % of disparity errors fall inside one sigma.
// The sparse ZNCC point matcher (features/stereo_point_matcher.hpp) uses the same model on its
// score curve, where the peak is a maximum: kappa = 2 s0 - s- - s+ (ZNCC units per px^2, the
// negated second difference of the scores at d-1, d, d+1), with its own table
// (defaultZnccPoints, fitted by `svslam fit-sigma --matcher points`).
#include <string>
#include <vector>

#include "core/status.hpp"

namespace svslam {

struct SigmaModel {
  std::vector<float> curvature;  // kappa knots, strictly increasing
  std::vector<float> sigma_px;   // sigma_d at each knot, pixels, > 0, non-increasing

  // The table fitted for census 9x7 with a 9x9 window on Middlebury (see docs/stereo.md).
  static SigmaModel defaultCensus();
  // The table fitted for the sparse ZNCC matcher (9x9 patch, corners) on Middlebury (see
  // docs/stereo.md); kappa = 2 s0 - s- - s+ of the ZNCC scores.
  static SigmaModel defaultZnccPoints();

  // sigma_d (px) for curvature kappa; kappa <= 0 or NaN gives the largest sigma.
  float sigmaFor(float kappa) const;
  Status validate() const;
};

// Fits a SigmaModel from (kappa, |error|) samples: the samples are split into `bins` groups of
// equal count by kappa; in each group sigma is the 68.27th percentile of |error| (so one sigma
// covers 68 % of that group's errors, gross mismatches included); the knots sit at each
// group's median kappa, and sigma is then made non-increasing (pool-adjacent-violators).
// Returns an error when there are fewer than 20 samples per bin.
Result<SigmaModel> fitSigmaModel(const std::vector<float>& kappa, const std::vector<float>& abs_err,
                                 int bins);

// Share of samples with |error| <= sigmaFor(kappa).
double sigmaCoverage(const SigmaModel& model, const std::vector<float>& kappa,
                     const std::vector<float>& abs_err);

}  // namespace svslam

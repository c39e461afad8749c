#pragma once
// A ground-truth stereo case (Middlebury or KITTI layout, or explicit files) loaded and, when
// asked, run through DenseStereo: shared by eval-disparity and fit-sigma.
#include <string>
#include <vector>

#include "core/executor.hpp"
#include "core/image.hpp"
#include "drivers/datasets/stereo_datasets.hpp"
#include "stereo/dense_stereo.hpp"

namespace svslam::cli {

struct LoadedCase {
  drivers::StereoGtCase info;
  ImageU8 left, right;
  ImageF32 gt;   // px, +inf unknown
  ImageU8 mask;  // empty = evaluate every known pixel
};

// Splits "a,b,c" into its non-empty parts.
std::vector<std::string> splitList(const std::string& s);

// Loads images, ground truth and mask of a case; with_images = false skips left/right. A case
// without a mask file gets one derived from its ground truth (nonOccludedMask) when
// derive_nonocc is true (the user asked for the non-occluded pixels).
Result<LoadedCase> loadCase(const drivers::StereoGtCase& info, bool with_images, bool derive_nonocc);

// Runs DenseStereo on a loaded case with `params` (max_disp <= 0 takes the case's own).
// `median_ms` (optional) receives the compute time.
Status computeDisparity(const LoadedCase& c, DenseStereoParams params, Executor& executor,
                        DisparityResult& out, double* compute_ms);

}  // namespace svslam::cli

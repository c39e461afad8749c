#pragma once
// Non-occluded mask derived from a left ground-truth disparity map, for data sets that ship no
// mask (Middlebury 2006 Aloe in ../shared/data). A left pixel (x, y) with disparity d is seen in
// the right image at x - d; it is occluded when x - d < 0 or when another left pixel with a
// disparity larger by more than `tolerance_px` lands on the same right pixel (a nearer surface
// hides it): forward warping with a z-buffer of the largest disparity per right pixel, as
// Middlebury's masks are made by cross-checking with a 1 px tolerance.
#include <cstdint>

#include "core/image.hpp"

namespace svslam {

// mask(x, y) = 255 where the ground truth is known (finite, > 0) and not occluded, else 0.
ImageU8 nonOccludedMask(ImageView<const float> gt_px, float tolerance_px = 1.0f);

}  // namespace svslam

#pragma once
// Stereo pairs with ground-truth disparity, found from the layout of a dataset folder.
//
// Recognised layouts (checked in this order):
//  (a) Middlebury v2 (tsukuba, venus, teddy, cones): imL.png, imR.png, groundtruth.png,
//      info.txt (line 1 = ground-truth scale, line 2 = max disparity, an exclusive bound:
//      disparities lie in [0, max - 1]), masks nonocc.png / all.png / disc.png.
//      name = folder name; mask = <mask_kind>.png.
//  (b) Middlebury 2006, OpenCV sample style (aloe): <p>L.png|jpg, <p>R.png|jpg, <p>GT.png with
//      disparity = value (scale 1), 0 = unknown. No mask file: mask = "" (the ground truth is 0
//      where unknown, occlusions included, so mask_kind is validated but has no effect).
//      max_disp = (the GT's largest value + 1) rounded up to a multiple of 16 (the GT is read).
//      `frame` selects <p> when several GT files are present (default: the first by name).
//      name = folder name.
//  (c) KITTI stereo 2012 (image_0/, image_1/, disp_noc/, disp_occ/) or 2015 (image_2/, image_3/,
//      disp_noc_0/, disp_occ_0/): mask_kind "nonocc" -> disp_noc*, "all" -> disp_occ*, "disc"
//      refused. `frame` is "000070_10.png", "000070_10" or "000070" (-> "_10"); by default the
//      first left image by name that has ground truth. uint16 PNG GT, scale 256; max_disp =
//      min(256, image width - 1) (the left image is read for its width); mask = "".
//      name = "<folder>_<frame without .png>", e.g. "kitti_stereo2012_000070_000070_10".
// Errors: folder missing -> notFound; mask_kind not one of nonocc/all/disc, or not offered by
// the layout -> invalidArgument; a layout recognised but a needed file missing -> notFound
// naming it; unreadable info.txt or GT -> corruptData (or the loader's error); no layout
// recognised -> notFound naming the folder and listing the expected layouts.
#include <string>

#include "core/status.hpp"

namespace svslam::drivers {

struct StereoGtCase {
  std::string name;   // short label for reports
  std::string left;   // rectified left image (loadGrey)
  std::string right;  // rectified right image (loadGrey)
  std::string gt;     // left-view ground-truth disparity: loadDisparity(gt, gt_scale)
  std::string mask;   // evaluation mask for loadMask, or "" = wherever the ground truth is known
  double gt_scale = 1.0;  // stored value / gt_scale = disparity in px
  int max_disp = 0;       // one past the largest disparity worth searching, px (exclusive bound)
};

Result<StereoGtCase> findStereoGtCase(const std::string& dir,
                                      const std::string& mask_kind = "nonocc",
                                      const std::string& frame = "");

}  // namespace svslam::drivers

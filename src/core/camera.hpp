#pragma once
// Camera models for a rectified stereo pair.
//
// Frames: camera frame x right, y down, z forward (optical axis), metres. Pixel (u, v) with u
// along x and v along y. Rectified pair: the right camera sits at +baseline_m along the left
// camera's x axis, both share f, cx, cy; disparity d = u_left - u_right > 0 and z = f b / d.
#include <cmath>
#include <string>

#include "core/status.hpp"

namespace svslam {

// Ideal pinhole (no distortion): u = fx x / z + cx, v = fy y / z + cy.
struct PinholeCamera {
  double fx_px = 0.0;
  double fy_px = 0.0;
  double cx_px = 0.0;
  double cy_px = 0.0;
  int width = 0;
  int height = 0;

  // Projects p_cam (z > 0 required) to pixels. Returns false when z <= 0.
  bool project(double x, double y, double z, double& u, double& v) const {
    if (!(z > 0.0)) return false;
    u = fx_px * x / z + cx_px;
    v = fy_px * y / z + cy_px;
    return true;
  }
  // Back-projects pixel (u, v) at depth z (metres) into the camera frame.
  void backProject(double u, double v, double z, double& x, double& y) const {
    x = (u - cx_px) * z / fx_px;
    y = (v - cy_px) * z / fy_px;
  }
  Status validate() const {
    auto finite = [](double a) { return std::isfinite(a); };
    if (!finite(fx_px) || !finite(fy_px) || !finite(cx_px) || !finite(cy_px))
      return Status::invalidArgument("camera intrinsics contain NaN or infinity");
    if (fx_px <= 0.0 || fy_px <= 0.0)
      return Status::invalidArgument("camera focal length must be > 0 px");
    if (width <= 0 || height <= 0) return Status::invalidArgument("camera size must be > 0");
    return Status::ok();
  }
};

// Rectified stereo pair: one focal length f (fx == fy after rectification), one principal point,
// baseline along +x of the left camera.
struct StereoCalibration {
  double f_px = 0.0;
  double cx_px = 0.0;
  double cy_px = 0.0;
  double baseline_m = 0.0;
  int width = 0;
  int height = 0;
  // Added to every measured disparity before triangulation (stereo/reprojection.hpp), px: the
  // estimator's online estimate of the pair's disparity offset (motion/disparity_offset.hpp);
  // 0 for a calibration as loaded.
  double disparity_offset_px = 0.0;
  // The calibration is exact by construction (rendered images): no calibration uncertainty is
  // added to the published pose covariance (slam/calibration_consider.hpp).
  bool exact = false;

  PinholeCamera leftCamera() const { return {f_px, f_px, cx_px, cy_px, width, height}; }
  // Depth of a disparity (pixels, > 0): z = f b / d.
  double depthFromDisparity(double d_px) const { return f_px * baseline_m / d_px; }
  double disparityFromDepth(double z_m) const { return f_px * baseline_m / z_m; }

  Status validate() const {
    if (!std::isfinite(f_px) || !std::isfinite(cx_px) || !std::isfinite(cy_px) ||
        !std::isfinite(baseline_m) || !std::isfinite(disparity_offset_px))
      return Status::invalidArgument("stereo calibration contains NaN or infinity");
    if (f_px <= 0.0) return Status::invalidArgument("stereo calibration: f_px must be > 0");
    if (baseline_m <= 0.0)
      return Status::invalidArgument("stereo calibration: baseline_m must be > 0");
    if (width <= 0 || height <= 0)
      return Status::invalidArgument("stereo calibration: image size must be > 0");
    return Status::ok();
  }
};

}  // namespace svslam

#pragma once
// 3D reprojection of a disparity map with per-point covariance (seed 001 sec 4.1).
//
// Left camera frame (x right, y down, z forward), rectified pair with focal f (px), principal
// point (cx, cy) and baseline b (m). For pixel (u, v) with disparity d (px):
//     z = f b / d,   x = (u - cx) b / d,   y = (v - cy) b / d.
// First-order propagation of the independent errors sigma_u = sigma_v = sigma_uv_px (image-plane
// localisation) and sigma_d (from the peak curvature):  Sigma_p = J diag(su^2, sv^2, sd^2) J^T,
//     J = d(x, y, z)/d(u, v, d) = [ b/d   0    -(u - cx) b / d^2 ]
//                                 [ 0     b/d  -(v - cy) b / d^2 ]
//                                 [ 0     0    -f b / d^2        ]
// so sigma_z = z^2 sigma_d / (f b), the familiar depth error of stereo.
#include <Eigen/Core>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam {

struct StereoPoint {
  Eigen::Vector3d p_cam;  // metres, left camera frame
  Eigen::Matrix3d cov;    // m^2
  float u_px = 0.0f;      // pixel of the left image
  float v_px = 0.0f;
  float d_px = 0.0f;  // disparity
  float sigma_d_px = 0.0f;
};

struct ReprojectionParams {
  double sigma_uv_px = 0.5;       // image-plane standard deviation of a pixel position, px, >= 0
  double min_disparity_px = 0.5;  // smaller disparities (too far, unstable) are skipped, px, > 0
  double max_depth_m = 1e9;       // points farther than this are skipped, m, > 0
  int step_px = 1;                // take every step-th pixel in x and y, >= 1
  Status validate() const;
};

// One point with covariance from (u, v, d, sigma_d), d the measured disparity: the point is
// triangulated at d + calib.disparity_offset_px (also what the result's d_px holds). A
// non-finite point when the offset takes a positive d to zero or below. Precondition: d > 0,
// calibration valid.
StereoPoint reprojectPixel(const StereoCalibration& calib, double u_px, double v_px, double d_px,
                           double sigma_d_px, double sigma_uv_px);

// Observation of a matched point from a dense disparity map, combining the stereo error with
// the 2D matching error (seed 001 sec 4.1, fig. 4). matching_error_px = 1: the dense 3D points
// X_i (covariance A_i from sigma_d alone) of the pixel nearest (u, v) and its 8 neighbours;
// matching_error_px = 0.5: the half-pixel points X_i/2 = (X_0 + X_i) / 2, A_i/2 = (A_0 + A_i) / 2
// (the surface assumed locally linear). Then
//     X = 1/n sum X_i,   A = 1/n sum (A_i + (X_i - X)(X_i - X)^T),
// over the n neighbours with a valid disparity (the centre must be valid, n >= min_valid).
// Other matching errors are rejected. Returns false when the pixel cannot be observed.
bool neighbourhoodPoint(ImageView<const float> disparity_px, ImageView<const float> sigma_d_px,
                        const StereoCalibration& calib, double u_px, double v_px,
                        double matching_error_px, int min_valid, StereoPoint& out);

// Every valid pixel (finite disparity and sigma) of a disparity map; `out` is cleared first.
Status reprojectDisparity(ImageView<const float> disparity_px, ImageView<const float> sigma_d_px,
                          const StereoCalibration& calib, const ReprojectionParams& params,
                          std::vector<StereoPoint>& out);

}  // namespace svslam

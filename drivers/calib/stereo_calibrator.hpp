#pragma once
// Chessboard stereo calibration (OpenCV calib3d): pairs of raw grey views in, the calibration
// file of the v4l2:/libcamera: sources and quality figures out. Pure computation (no files,
// threads or clocks); it lives in drivers/ because svslam_src does not link OpenCV.
//
// Per pair (addPair): findChessboardCorners on each view, cornerSubPix (window half-size 1/3 of
// the smallest corner spacing, clamped to [2, 11] px), then the pair is accepted or rejected with
// a reason, checked in this order:
//   "board not found in left|right|left and right"
//   "blurred (left|right sharpness S < min_sharpness)"  S = variance of the Laplacian (3x3
//       aperture, 8-bit grey levels^2) inside the bounding box of the detected corners
//       (sharp boards score 4000-9000 in OpenCV's sample pairs; a Gaussian blur of sigma 3 px
//       takes a full-contrast board to ~200, the default limit)
//   "duplicate of PAIR (corners moved < min_motion_px)"  mean corner displacement, in both
//       views, against every accepted pair; a still board adds nothing (live grabbing)
// A view size different from the first pair's, or left and right of different sizes, is an
// error (the inputs are mixed), not a rejection.
//
// calibrate(): object points z = 0, x = col * square_m, y = row * square_m (metres; corner 0 is
// the first corner OpenCV reports). calibrateCamera per camera (k1 k2 p1 p2 k3), then
// stereoCalibrate starting from those intrinsics: either CALIB_FIX_INTRINSIC (only R, T) or a
// joint refinement of both cameras' intrinsics with R, T (CALIB_USE_INTRINSIC_GUESS; default,
// it gives the lower pair RMS and epipolar error on real data, see docs/cameras.md). A pair whose
// stereo reprojection RMS (either view) exceeds max_view_rms_px is rejected as "reprojection
// outlier" and the calibration is redone once without it. Then stereoRectify (Bouguet,
// CALIB_ZERO_DISPARITY, alpha 0: exactly what the v4l2:/libcamera: sources do with the file).
//
// Coverage: each view is divided into a 3x3 grid; a camera's coverage is the fraction of the 9
// cells holding at least one detected corner of an accepted pair. Below min_coverage (either
// camera; default 0.75 = at least 7 of 9 cells) calibrate() fails with "poor coverage": the
// distortion towards the uncovered edges and image corners would be extrapolated.
//
// Epipolar error: every detected corner of every used pair is undistorted and rectified
// (undistortPoints with R1,P1 / R2,P2); the error of a corner is |y_left - y_right| in rectified
// px. Mean and max are reported.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "drivers/files/stereo_calibration_file.hpp"

namespace svslam::drivers {

struct StereoCalibrationParams {
  int board_cols = 9;            // inner corners per board row, [3, 100]
  int board_rows = 6;            // inner corners per board column, [3, 100]
  double square_m = 0.025;       // side of one board square, metres, (0, 10]
  double min_sharpness = 200.0;  // variance of the Laplacian in the board box, grey^2, >= 0
  double min_motion_px = 2.0;    // mean corner motion between accepted pairs, px, >= 0
  int min_pairs = 6;             // accepted pairs needed, [3, 1000]
  double min_coverage = 0.75;    // fraction of 3x3 image cells the corners touch, [0, 1]
  double max_view_rms_px = 1.0;  // per-pair stereo reprojection RMS limit, px, > 0
  bool fix_intrinsic = false;    // stereoCalibrate with CALIB_FIX_INTRINSIC instead of joint
  // The first violated range as a message naming the field; ok when all are in range.
  Status validate() const;
};

struct PairRejection {
  std::string pair;    // the name given to addPair
  std::string reason;  // see the top of this header
};

struct StereoCalibrationResult {
  StereoCalibrationFile file;     // what the v4l2:/libcamera: sources read
  cv::Mat R1, R2, P1, P2, Q;      // stereoRectify output (CALIB_ZERO_DISPARITY, alpha 0)
  double rms_left_px = 0.0;       // calibrateCamera RMS reprojection error, left camera
  double rms_right_px = 0.0;      // same, right camera
  double rms_pair_px = 0.0;       // stereoCalibrate RMS over both views
  // The left camera's calibrateCamera standard deviations: principal point (rms of cx and cy),
  // px, and focal length relative to it: slam.calibration_sigma_principal_point_px and a part of
  // slam.calibration_sigma_scale (slam/calibration_consider.hpp).
  double sigma_principal_point_left_px = 0.0;
  double sigma_f_left_rel = 0.0;
  double epipolar_mean_px = 0.0;  // mean |y_l - y_r| of rectified corners, px
  double epipolar_max_px = 0.0;   // max of the same
  double coverage_left = 0.0;     // fraction of 3x3 cells with corners, [0, 1]
  double coverage_right = 0.0;
  double baseline_m = 0.0;              // rectified baseline, -P2(0,3) / P2(0,0), metres
  std::vector<std::string> used;        // names of the pairs that went into the result
  std::vector<PairRejection> rejected;  // every pair not used, in arrival order
};

class StereoCalibrator {
 public:
  explicit StereoCalibrator(StereoCalibrationParams params);
  // The params' validate() result; addPair/calibrate fail with it when not ok.
  const Status& initStatus() const { return init_; }

  // Detects the board in one raw pair (8-bit grey, same size). `accepted` tells whether the pair
  // was kept; a rejection is recorded with its reason (rejections()). Errors: bad image type,
  // left/right size differ, size differs from the first pair's.
  Status addPair(const cv::Mat& left, const cv::Mat& right, const std::string& name,
                 bool& accepted);
  int acceptedPairs() const { return static_cast<int>(views_.size()); }
  const std::vector<PairRejection>& rejections() const { return rejected_; }
  cv::Size imageSize() const { return size_; }

  // Calibrates from the accepted pairs (see top). Errors name the problem: no pair at all, the
  // board found in no pair, too few usable pairs (with the rejection counts), poor coverage.
  Result<StereoCalibrationResult> calibrate() const;

 private:
  struct View {
    std::string name;
    std::vector<cv::Point2f> left, right;
  };
  StereoCalibrationParams params_;
  Status init_;
  cv::Size size_;
  int pairs_seen_ = 0;
  int boards_found_ = 0;  // pairs with the board in both views (before sharpness / duplicates)
  std::vector<View> views_;
  std::vector<PairRejection> rejected_;
};

// The rectified pair side by side (BGR, 2W x H) with a horizontal line every `line_step_px` rows,
// for checking by eye that rows agree. left/right: raw 8-bit grey views of the calibrated size.
cv::Mat renderRectifiedCheck(const StereoCalibrationResult& r, const cv::Mat& left,
                             const cv::Mat& right, int line_step_px = 32);

}  // namespace svslam::drivers

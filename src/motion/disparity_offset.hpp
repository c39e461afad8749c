#pragma once
// Online self-calibration of a constant disparity offset of a rectified stereo pair.
//
// Model: the true disparity of a point is the measured one plus delta (px), the same for every
// point of the sequence (a residual of the calibration or rectification, or a sub-pixel bias
// of the matcher). A point triangulated from the measured disparity d, p = q b / d with
// q = (u - c_x, v - c_y, f), is then at
//     p(delta) = q b / (d + delta) = s p,   s = 1 / (1 + delta z / (f b))          (z = p.z)
// and its covariance becomes s^2 A (first order; the disparity term scales as s^4 through the
// depth, negligible for |delta| << d). A constant offset distorts depth by delta z^2 / (f b):
// near and far points move by different amounts, so a rigid motion cannot fit the two frames of a
// pair exactly unless delta is right. That makes delta observable from the frame-to-frame
// motion (with translation along the view; a pure rotation carries no information about it).
//
// Per frame, around the motion estimate u = T_cur_prev and the current offset (both frames'
// points already corrected with it): residuals r_i = X'_i - R X_i - t, weights
// W_i = (A'_i + R A_i R^T)^-1 (motion/visual_motion.hpp), Jacobians J_i = [[R X_i]x, -I] for u
// and j_i = dr_i/ddelta = -(z'_i / (f b)) X'_i + (z_i / (f b)) R X_i, evaluated at the point
// the two frames agree on, Xm_i = (X_i + R^T (X'_i - t)) / 2 and R Xm_i + t (at the measured
// points, their depth noise would enter both j_i and r_i and bias the estimate upwards by about
// 4 z sigma_z^2 / (f b) per point: errors in variables). With
//     H = sum J^T W J, h = sum J^T W j, c = sum j^T W j, g = sum J^T W r, e = sum j^T W r,
// the motion is profiled out (Schur complement):
//     I_k = c - h^T H^-1 h,   delta_k = delta + (h^T H^-1 g - e) / I_k,
// an estimate of the offset with information I_k (px^-2). The offset is their
// information-weighted mean with a zero-mean prior of sigma prior_sigma_px (sub-pixel):
//     delta = sum I_k delta_k / (prior_sigma_px^-2 + sum I_k),
// clamped to [-max_abs_px, max_abs_px]. A frame whose delta_k lies more than gate_sigma
// standard deviations (sqrt(1 / I_k + 1 / information)) from the current offset is not used
// (a wrong match set, a moving object), nor is one with fewer than min_points inliers or with
// I_k below min_information (the offset not observable in that frame).
// The information assumes independent point errors; it only weighs the frames against each
// other and against the prior.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/status.hpp"
#include "motion/visual_motion.hpp"

namespace svslam {

struct DisparityOffsetParams {
  bool enabled = true;
  double prior_sigma_px = 0.5;  // prior on the offset, zero mean, px, > 0 (sub-pixel, weakly)
  double max_abs_px = 1.0;      // the offset is clamped to +- this, px, > 0
  double gate_sigma = 5.0;      // frame estimates further than this many sigma are not used, > 0
  int min_points = 30;          // inliers a frame needs to contribute, >= 3
  // Observability: a frame contributes only when it determines the offset on its own to within
  // 1 / sqrt(min_information) px (4: 0.5 px). A scene at one depth (a camera looking down on
  // flat ground) or a pure rotation does not, and its tiny, easily biased information would
  // otherwise add up over a long run. px^-2, >= 0.
  double min_information = 4.0;
  Status validate() const;
};

// s = 1 / (1 + delta z / (f b)) of the header for a point at depth z_m (m), or 1 when the
// correction is not defined (z <= 0, or 1 + delta z / (f b) <= 0.1).
double disparityOffsetScale(double z_m, double f_times_b, double delta_px);

struct DisparityOffsetFrame {
  bool used = false;        // the frame contributed
  double estimate_px = 0;   // delta_k (0 when not computed)
  double information = 0;   // I_k, px^-2
};

class DisparityOffsetEstimator {
 public:
  // f_times_b: focal length (px) times baseline (m) of the rectified pair, > 0.
  DisparityOffsetEstimator(const DisparityOffsetParams& params, double f_times_b);
  const Status& initStatus() const { return init_status_; }

  // One frame: `pairs` corrected with offsetPx(), `inlier` the motion's inlier flags (one per
  // pair), T_cur_prev the motion estimated from them. Updates the offset.
  Status process(const std::vector<PointPair>& pairs, const std::vector<std::uint8_t>& inlier,
                 const Eigen::Isometry3d& T_cur_prev, DisparityOffsetFrame& out);

  double offsetPx() const { return offset_px_; }
  // Standard deviation of the offset from the accumulated information (px).
  double sigmaPx() const;
  int framesUsed() const { return frames_used_; }

 private:
  DisparityOffsetParams params_;
  double f_times_b_;
  Status init_status_;
  double offset_px_ = 0;
  double information_ = 0;     // prior + frames, px^-2
  double weighted_sum_ = 0;    // sum I_k delta_k
  int frames_used_ = 0;
};

}  // namespace svslam

#pragma once
// Inter-frame rotation by direct image alignment on a coarse pyramid: the prediction of the
// temporal search when the constant-velocity one fails (a sharp turn).
//
// Model: a pure rotation R = R_cur_prev maps a pixel x of the previous left image to
// w(x; R) = pi(K R K^-1 [x; 1]) in the current one (translation is neglected: at the coarse
// levels its parallax is small next to a turn's flow). With an affine brightness change
// (gain a, bias b) the residual of pixel x is
//   r(x) = a I_cur(w(x; R)) + b - I_prev(x),
// minimised over (dtheta, a, b), R = exp([dtheta]x) R_hat, by Gauss-Newton with Huber weights
// (threshold huber_grey), coarse to fine over the levels [finest_level, coarsest_level] of a
// 2x2-mean pyramid (level L: pixel centres at (x + 0.5) 2^L - 0.5, focal length f / 2^L).
// The derivative of w with respect to dtheta at q = R K^-1 [x; 1]: dq/dtheta = -[q]x, and
// dw/dq = [f/q_z, 0, -f q_x/q_z^2; 0, f/q_z, -f q_y/q_z^2].
// Several starting rotations may be given; each is also searched over a grid at the coarsest
// level (rotations about the camera's x and y axes within +-search_deg in steps of step_deg,
// composed on the left), whose lowest-cost rotation starts one more Gauss-Newton descent. The
// result is the descent of lowest final cost.
#include <Eigen/Core>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam {

struct RotationAlignmentParams {
  int coarsest_level = 4;        // pyramid level where the alignment starts (1/16 size), 1..6
  int finest_level = 3;          // level where it ends, 0..coarsest_level
  int iterations = 10;           // Gauss-Newton iterations per level, >= 1
  double huber_grey = 10.0;      // Huber threshold of the residual, grey levels, > 0
  double border_fraction = 0.05; // pixels this close to the border (share of the size) unused
  double search_deg = 12.0;      // half-range of the coarse grid search, deg, >= 0 (0: none)
  double step_deg = 2.0;         // its step, deg, > 0
  Status validate() const;
};

struct RotationAlignmentResult {
  Eigen::Matrix3d R_cur_prev = Eigen::Matrix3d::Identity();
  double rms_grey = 0.0;  // robust RMS residual at the finest level, grey levels
  double overlap = 0.0;   // share of the finest level's pixels that stayed inside the image
  int start = -1;  // the descent that won: index into the starts, or starts.size() for the grid's
};

class RotationAlignment {
 public:
  // Preallocates the pyramids of width x height images.
  RotationAlignment(const RotationAlignmentParams& params, int width, int height);
  const Status& initStatus() const { return init_status_; }
  // prev, cur: left images of the same size as at construction. starts: starting rotations
  // (at least one). Returns failedPrecondition when no start keeps 30 % of the pixels in view.
  Status process(ImageView<const std::uint8_t> prev, ImageView<const std::uint8_t> cur,
                 const PinholeCamera& camera, const std::vector<Eigen::Matrix3d>& starts,
                 RotationAlignmentResult& out);

 private:
  void buildPyramid(ImageView<const std::uint8_t> img, std::vector<Image<float>>& pyr) const;
  // Robust cost per used pixel of rotation R and brightness (a, b) at one level; with H and g,
  // also adds the Gauss-Newton normal equations of (dtheta, da, db). overlap: share of the
  // level's pixels that stayed in view. Infinity when under 50 pixels did.
  double accumulate(int level, const PinholeCamera& cam, const Eigen::Matrix3d& R, double a,
                    double b, Eigen::Matrix<double, 5, 5>* H, Eigen::Matrix<double, 5, 1>* g,
                    double& overlap) const;
  // Gauss-Newton at one level from R, a, b (updated in place); returns the robust cost per used
  // pixel of the last step's linearisation point.
  double alignLevel(int level, const PinholeCamera& cam, Eigen::Matrix3d& R, double& a,
                    double& b, double& overlap) const;

  RotationAlignmentParams params_;
  Status init_status_;
  int width_ = 0, height_ = 0;
  std::vector<Image<float>> prev_pyr_, cur_pyr_;  // index = level
  std::vector<Eigen::Matrix3d> descents_;
};

}  // namespace svslam

#pragma once
// Stereo matching of interest points on a rectified pair (seed 001 sec 3.2, seed 002 sec 2.2).
//
// 1. Row search: each left point (x, y) is compared by ZNCC (patch_similarity.hpp) with the
//    right image along the same row, at integer disparities d in [min_disp, max_disp) or, where
//    a dense disparity prior exists, in [prior - prior_radius, prior + prior_radius].
//    Accepted when zncc_best >= min_zncc and the ratio test holds on the dissimilarity
//    c = 1 - zncc: max(c_best, ratio_floor) <= ratio * c_second, the second best being the
//    highest other local maximum of the score curve at |d - d_best| > 1 (the flanks of the best
//    peak do not compete; the floor: on a repeated pattern both peaks are near 1 and their tiny
//    dissimilarities would compare by sampling noise).
//    Sub-pixel disparity by a parabola through the scores at d-1, d, d+1, then (subpixel =
//    kRefine, the default) refined by Gauss-Newton of the right image's Lanczos-resampled patch
//    against the left one (subpixel_refine.hpp), which removes the parabola's pull towards
//    integer disparities; when the refinement does not converge the parabola value stays.
// 2. Disparity continuity (seed 002 eq. 10): the 3 nearest accepted neighbours (left image) of
//    each match must all satisfy |d_i - d_n| < continuity_threshold_px; otherwise rejected.
// 3. Recovery (seed 002 eq. 11): the kept matches are Delaunay-triangulated in the left image;
//    for each rejected point inside a triangle (V1, V2, V3) of the left image, every local
//    ZNCC maximum (>= min_zncc) on the row inside the disparity span of the right triangle
//    (V1 - d1, V2 - d2, V3 - d3), widened by recovery_margin_px, is a candidate P_B; the
//    candidate minimising  sum_i | |P_A - P_AVi| - |P_B - P_BVi| |  is taken when that sum is
//    below recovery_dist_th_px.
// Every match carries sigma_d_px, its disparity standard deviation. With sigma_mode = kFixed
// (the default) it is sigma_d_px, a documented constant of the size the calibration gives the
// typical match (docs/stereo.md). With kCurvature it comes from the sharpness of the score peak
// (seed 001 fig. 3):
// kappa = 2 s(d) - s(d-1) - s(d+1) (ZNCC units / px^2, the parabola of the sub-pixel fit has
// second derivative -kappa), mapped through the calibrated table sigma_model (SigmaModel, fitted
// on ground truth by `svslam fit-sigma --matcher points` so that ~68 % of disparity errors fall
// inside one sigma), never below min_sigma_d_px. kCurvature is not the default because, measured
// downstream, it did not make the EKF's covariance more honest on real data and its EuRoC
// trajectory was no better than VO (docs/slam.md).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/image.hpp"
#include "core/status.hpp"
#include "features/delaunay.hpp"
#include "features/patch_similarity.hpp"
#include "features/subpixel_refine.hpp"
#include "stereo/sigma_model.hpp"

namespace svslam {

enum class StereoSigmaMode {
  kCurvature,  // sigma_d from the ZNCC peak curvature through sigma_model
  kFixed,      // sigma_d = sigma_d_px for every match (default)
};

enum class SubpixelMethod {
  kParabola,  // parabola through the three scores around the integer peak
  kRefine,    // the parabola, then Gauss-Newton refinement (refineDisparity)
};

struct StereoMatchParams {
  int patch_half_px = 4;        // ZNCC patch (2h+1)^2, px, 1..15
  int min_disp_px = 0;          // searched disparities [min, max), px, >= 0
  int max_disp_px = 128;        // > min_disp_px
  float min_zncc = 0.8f;        // acceptance threshold, -1..1
  float ratio = 0.8f;           // ratio test on 1 - zncc, (0, 1]
  float ratio_floor = 0.05f;    // c_best is taken as at least this in the ratio test, so two
                                // near-perfect peaks (repeated texture) are ambiguous, 0..1
  int prior_radius_px = 2;      // search half-range around a dense prior, px, >= 1
  bool continuity_check = true;
  float continuity_threshold_px = 10.0f;  // d_th of seed 002 eq. 10, px, > 0
  bool recovery = true;
  float recovery_dist_th_px = 3.0f;  // Dist_th of seed 002 eq. 11, px, > 0
  int recovery_margin_px = 2;        // widening of the triangle's disparity span, px, >= 0
  StereoSigmaMode sigma_mode = StereoSigmaMode::kFixed;
  float sigma_d_px = 0.3f;      // kFixed: disparity standard deviation of every match, px, > 0
  float min_sigma_d_px = 0.0f;  // kCurvature: floor of the calibrated sigma_d, px, >= 0
  SigmaModel sigma_model = SigmaModel::defaultZnccPoints();  // kCurvature: kappa -> sigma_d
  SubpixelMethod subpixel = SubpixelMethod::kRefine;
  SubpixelRefineParams refine;  // kRefine
  Status validate() const;
};

struct StereoMatch {
  int index = -1;     // into the input points
  float u_px = 0;     // left image position (the input point)
  float v_px = 0;
  float d_px = 0;     // sub-pixel disparity, u_right = u - d
  float sigma_d_px = 0;
  float curvature = 0;  // kappa = 2 s(d) - s(d-1) - s(d+1) at the integer peak, 1/px^2, >= 0
  float score = 0;    // zncc at the integer peak
  bool recovered = false;  // rejected by the continuity check, then recovered
  bool refined = false;    // d_px from the Gauss-Newton refinement (else the parabola)
};

struct StereoMatchStats {
  int candidates = 0;         // input points with a searchable patch
  int row_matched = 0;        // passing the row search
  int continuity_rejected = 0;
  int recovered = 0;
  int matched = 0;            // in the output
  int refined = 0;            // output matches with a refined disparity (kRefine)
};

class StereoPointMatcher {
 public:
  explicit StereoPointMatcher(const StereoMatchParams& params);
  const Status& initStatus() const { return init_status_; }

  // Matches the points `pts_px` of `left` in `right` (same size). `prior_disp_px` is a dense
  // disparity of the left image (+inf or NaN where unknown) or an empty view.
  // `ranges`, when given, holds one integer disparity interval [d0, d1] per point (e.g. from a
  // right-image region of interest), intersected with the parameter range; d0 > d1 skips the
  // point.
  Status process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                 const std::vector<Eigen::Vector2f>& pts_px, ImageView<const float> prior_disp_px,
                 std::vector<StereoMatch>& out, StereoMatchStats& stats,
                 const std::vector<Eigen::Vector2i>* ranges = nullptr);

  // Row search for one left pixel (x, y) over disparities [d0, d1] (clipped to the parameter
  // range), with the same acceptance tests as process(); false when not matched.
  bool matchPoint(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right, int x,
                  int y, int d0, int d1, StereoMatch& out);

 private:
  // Best integer disparity of point (x, y) over [d0, d1]; false when not accepted.
  bool searchRow(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right, int x,
                 int y, int d0, int d1, StereoMatch& m);
  // scores_[d - d0] = zncc of the left patch `ps` (centre (ps.x, y)) against the right patch at
  // (ps.x - d, y), d in [d0, d1]. Precondition: every right patch inside the image.
  void scanRow(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
               const PatchStats& ps, int y, int d0, int d1);
  // Sub-pixel disparity, curvature and sigma_d of `m` from the scores at d-1, d, d+1 at left
  // pixel (x, y); with kRefine the disparity is then refined on the images.
  void setPeak(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right, int x,
               int y, int d, float sm, float s0, float sp, StereoMatch& m);
  void continuityCheck(std::vector<StereoMatch>& matches, std::vector<StereoMatch>& rejected);
  void recover(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
               std::vector<StereoMatch>& kept, const std::vector<StereoMatch>& rejected);

  StereoMatchParams params_;
  Status init_status_;
  std::vector<float> scores_;
  std::vector<float> row_;  // znccRow output, right-image order
  ZnccRowScratch zncc_scratch_;
  std::vector<StereoMatch> rejected_;
  std::vector<std::uint8_t> keep_;
  std::vector<Eigen::Vector2d> tri_pts_;
  std::vector<Triangle2> tris_;
  Delaunay delaunay_;
};

}  // namespace svslam

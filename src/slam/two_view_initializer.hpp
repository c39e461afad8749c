#pragma once
// Relative pose of two calibrated views from point correspondences, the scale left free: the
// monocular map start (Mur-Artal et al. 2015, "ORB-SLAM", section IV; Hartley & Zisserman).
//
// Frames and units. x0[i], x1[i] are normalised image coordinates ((u - cx) / f, (v - cy) / f)
// of correspondence i in views 0 and 1; X0 = (x0, 1) and X1 = (x1, 1) their homogeneous forms.
// A point p0 in view 0's camera frame (x right, y down, z forward) is at
//     p1 = R_1_0 p0 + t_1_0
// in view 1's frame. |t_1_0| = 1: the map's unit is the baseline. Pixel quantities (thresholds,
// errors) are normalised-coordinate distances times f_px.
//
// 1. Two models, each by RANSAC over the same hypothesis sets (8 distinct correspondences per
//    iteration, drawn by a partial Fisher-Yates shuffle), both on Hartley-normalised points
//    (centroid at the origin, mean distance sqrt(2); each view normalised once over all points):
//    - the essential matrix E = [t]x R, X1^T E X0 = 0: the 8-point solution (the eigenvector of
//      the smallest eigenvalue of A^T A), denormalised, then projected onto the essential
//      matrices (singular values (1, 1, 0));
//    - the homography H, X1 ~ H X0 (H = R + t n^T / d for the plane n^T p0 = d): the DLT
//      solution of the same 8 points, denormalised.
//    Scores (ORB-SLAM's, sigma = inlier_threshold_px, e2 the squared error in px^2): E, the
//    distance of each point to its epipolar line in each image; H, the symmetric transfer error
//    (x1 against H x0, x0 against H^-1 x1). Per point and direction: when e2 / sigma^2 exceeds
//    3.841 (E, chi-square 1 dof at 95 %) or 5.991 (H, 2 dof) the point is not an inlier of the
//    hypothesis, otherwise the score gains 5.991 - e2 / sigma^2. The best hypothesis of each
//    model is then refitted to all its inliers (least squares, same solvers) while that raises
//    its score (at most 3 times). S_E and S_H the final scores, score_ratio_h = S_H / (S_H + S_E);
//    the homography is chosen when score_ratio_h > homography_ratio, else the essential matrix.
// 2. Pose candidates of the chosen model: E, its four (R, t) factorisations (Hartley &
//    Zisserman 9.6.2); H, Faugeras' eight (R, t, n) (ORB-SLAM's ReconstructH). Each candidate is
//    checked over the model's inliers (ORB-SLAM's CheckRT): the midpoint triangulation p0 of the
//    two rays is good when it is in front of both views (depth > 0), its triangulation angle
//    (between the rays from the two camera centres) is at least 0.36 deg (cos < 0.99998, the
//    floor below which depth is noise), and its reprojection error is below 2 sigma px in both
//    images. The candidate with the most good points is kept when
//      - it has at least min_inliers good points (else "too few inliers", or "low parallax" when
//        the rotation-compensated angle between the bearings of the model's inliers has a
//        median below min_parallax_deg for every candidate rotation, e.g. a pure rotation),
//      - the median triangulation angle of its good points is at least min_parallax_deg (else
//        "low parallax"),
//      - every other candidate has fewer than min_best_ratio times its good points (else
//        "ambiguous"; ORB-SLAM: 0.7 for E, 0.75 for H).
//    Otherwise out.initialised = false with out.why (also "too few correspondences": fewer than
//    max(8, min_inliers) correspondences; "no model": every hypothesis degenerate).
//    Refinements (Levenberg-Marquardt, numerical Jacobian): the chosen homography, before its
//    decomposition, on its inliers (symmetric transfer error, px); the essential matrix's best
//    pose, before the final check, on its good points (Sampson distance to [t]x R, px; R and
//    the direction of t, 5 parameters). The final check of the refined pose gives out.inlier,
//    out.p0, num_inliers and median_parallax_deg.
//
// Randomness: a 64-bit Mersenne twister seeded from params.seed and the caller's stream number,
// the sample indices formed from its raw 64-bit outputs (rng() % n): the same input, seed and
// stream give the same result on every platform.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/status.hpp"

namespace svslam {

struct TwoViewInitializerParams {
  int ransac_iterations = 200;       // hypotheses per model, [1, 100000]
  double inlier_threshold_px = 1.0;  // sigma of the chi-square tests above, px, > 0
  int min_inliers = 50;              // good (triangulated) points needed, >= 8
  double min_parallax_deg = 1.0;     // median triangulation angle of the good points, deg, (0, 90]
  double homography_ratio = 0.45;    // H chosen when S_H / (S_H + S_E) > this, [0, 1]
  double min_best_ratio = 0.75;      // ambiguous when the second best candidate pose has at
                                     // least this fraction of the best's good points, (0, 1]
  std::uint64_t seed = 1;            // random seed (with the caller's stream number)
  Status validate() const;
};

struct TwoViewResult {
  enum class Model { kNone, kEssential, kHomography };
  bool initialised = false;
  Model model = Model::kNone;  // the model chosen by score (also when not initialised)
  const char* why = "";        // when not initialised: the reason (see above), a static string
  Eigen::Matrix3d R_1_0 = Eigen::Matrix3d::Identity();  // p1 = R_1_0 p0 + t_1_0
  Eigen::Vector3d t_1_0 = Eigen::Vector3d::Zero();      // unit norm when initialised
  std::vector<std::uint8_t> inlier;  // per correspondence: 1 for a good point of the kept pose
  std::vector<Eigen::Vector3d> p0;   // per correspondence: the point in view 0's frame (unit
                                     // baseline), valid where inlier == 1, else zero
  int num_inliers = 0;               // good points of the kept pose (also set when refused
                                     // for its parallax or as ambiguous)
  double median_parallax_deg = 0;    // their median triangulation angle; when not initialised
                                     // for low parallax, the rotation-compensated estimate
  double score_ratio_h = 0;          // S_H / (S_H + S_E)
};

class TwoViewInitializer {
 public:
  explicit TwoViewInitializer(const TwoViewInitializerParams& params);
  const Status& initStatus() const { return init_status_; }

  // x0[i], x1[i]: normalised image coordinates of correspondence i in views 0 and 1 (see
  // above); f_px converts the pixel thresholds. An error Status for bad input (sizes differ,
  // non-finite coordinates, f_px not finite and > 0) or bad params; "not initialised" is not an
  // error: out.initialised = false and out.why says why.
  Status process(const std::vector<Eigen::Vector2d>& x0, const std::vector<Eigen::Vector2d>& x1,
                 double f_px, std::uint64_t stream, TwoViewResult& out);

 private:
  struct Candidate {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
  };
  // Good points of a candidate over the model inliers mask (CheckRT); fills good_ / pts_ and,
  // when parallax is not null, the triangulation angles (deg) of the good points.
  int checkPose(const Candidate& c, const std::vector<std::uint8_t>& mask,
                std::vector<double>* parallax);

  TwoViewInitializerParams params_;
  Status init_status_;
  // Scratch, reused across calls.
  const std::vector<Eigen::Vector2d>* x0_ = nullptr;
  const std::vector<Eigen::Vector2d>* x1_ = nullptr;
  double f_px_ = 1;
  std::vector<Eigen::Vector2d> n0_, n1_;  // Hartley-normalised points
  std::vector<int> perm_, fit_idx_;
  std::vector<std::uint8_t> mask_e_, mask_h_, mask_tmp_, good_;
  std::vector<Eigen::Vector3d> pts_;
  std::vector<double> angles_;
};

}  // namespace svslam

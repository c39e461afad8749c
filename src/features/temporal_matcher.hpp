#pragma once
// Frame-to-frame matching of stereo points (seed 001 sec 3.2 and [11], seed 000 "combine
// signal and geometric information").
//
// Prediction: each previous point X (previous left camera frame, metres) is moved by the
// predicted motion T_cur_prev and projected into the current left image; current points within
// search_radius_px of that prediction are candidates.
// Signal: ZNCC of the (2h+1)^2 patches of the previous and current left images; the best
// candidate must reach min_zncc and pass the ratio test c_best <= ratio * c_second on
// c = 1 - zncc; a current point keeps only its best previous point (one-to-one).
// Geometry of local groups: a rigid motion preserves 3D distances. For match i and each of its
// group_size nearest matches j (previous image), D = |X_i - X_j| and D' = |X'_i - X'_j| must
// agree within group_n_sigma standard deviations, var = u^T (A_i + A_j) u + u'^T (A'_i + A'_j) u'
// (u, u' the unit directions); a match is kept when at least group_min_fraction of its group
// agrees.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam {

struct TemporalMatchParams {
  int patch_half_px = 5;            // ZNCC patch (2h+1)^2, px, 1..15
  float search_radius_px = 30.0f;   // around the predicted position, px, > 0
  float min_zncc = 0.8f;            // -1..1
  float ratio = 0.9f;               // ratio test on 1 - zncc, (0, 1]
  int group_size = 6;               // neighbours of the geometric check, 0 disables, 0..32
  double group_n_sigma = 3.0;       // tolerance in standard deviations, > 0
  double group_min_fraction = 0.5;  // share of the group that must agree, 0..1
  Status validate() const;
};

// A stereo point of one frame: left image position and 3D point with covariance.
struct TrackPoint {
  float u_px = 0, v_px = 0;
  Eigen::Vector3d p_cam = Eigen::Vector3d::Zero();  // metres, left camera frame
  Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();  // m^2
  float d_px = 0, sigma_d_px = 0;  // disparity and its standard deviation (stereo match)
};

struct TemporalMatch {
  int prev = -1;  // index into the previous points
  int cur = -1;   // index into the current points
  float score = 0;  // zncc
};

struct TemporalMatchStats {
  int predicted = 0;      // previous points projecting inside the current image
  int signal_matched = 0;  // after ZNCC + ratio + one-to-one
  int geometry_rejected = 0;
  int matched = 0;
};

class TemporalMatcher {
 public:
  explicit TemporalMatcher(const TemporalMatchParams& params);
  const Status& initStatus() const { return init_status_; }

  // `out` is sorted by previous index. `search_radius_px` > 0 overrides the parameter (used
  // after a tracking loss).
  // `regions`, when given, holds one rectangle [x0, x1) x [y0, y1) per previous point (its
  // cluster's region of interest in the current image; x0 >= x1 = no restriction): candidates
  // outside it are not considered.
  Status process(ImageView<const std::uint8_t> prev_img, const std::vector<TrackPoint>& prev,
                 ImageView<const std::uint8_t> cur_img, const std::vector<TrackPoint>& cur,
                 const Eigen::Isometry3d& T_cur_prev_pred, const PinholeCamera& camera,
                 std::vector<TemporalMatch>& out, TemporalMatchStats& stats,
                 float search_radius_px = 0.0f, const std::vector<Eigen::Vector4i>* regions = nullptr);

 private:
  void buildGrid(const std::vector<TrackPoint>& cur, int width, int height, float cell);
  void geometricCheck(const std::vector<TrackPoint>& prev, const std::vector<TrackPoint>& cur,
                      std::vector<TemporalMatch>& matches);

  TemporalMatchParams params_;
  Status init_status_;
  // Grid of the current points: cell c holds order_[start_[c] .. start_[c + 1]).
  int grid_w_ = 0, grid_h_ = 0;
  float cell_ = 1;
  std::vector<int> start_, order_, fill_;
  std::vector<int> best_prev_of_cur_;
  std::vector<float> best_score_of_cur_;
  std::vector<TemporalMatch> cand_;
  std::vector<std::uint8_t> keep_;
  std::vector<std::pair<float, int>> neighbours_;  // geometric check: (squared px distance, match)
};

}  // namespace svslam

#pragma once
// Geometric verification of a place-recognition candidate (seed 000: "re-perceive"; seed 002
// sec 4): the query keyframe's ORB descriptors are matched to the candidate's (mutual nearest
// neighbours in Hamming distance, at most max_hamming bits, best / second-best distance ratio
// below max_ratio), the matched stereo points form 3D-3D pairs
//   p_prev = point in the candidate's left camera frame, p_cur = the same in the query's,
// and the existing visual motion estimation (motion/visual_motion.hpp: seeded RANSAC, weighted
// Umeyama + Gauss-Newton on Mahalanobis residuals, k-sigma rejection, Haralick covariance)
// gives T_query_candidate = T_world_query^-1 T_world_candidate and its 6x6 covariance, ordered
// [dtheta rad, dt m] with R = exp([dtheta]x) R_hat, t = t_hat + dt.
// Accepted when at least min_inliers pairs survive, they are at least min_inlier_fraction of the
// matches and their RMS Mahalanobis residual is at most max_rms_mahalanobis. A look-alike place
// (same texture, other geometry) fails here: its descriptor matches do not share one rigid
// motion. Consistency over time and with the odometry is decided later (loop_consistency.hpp).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "loop/keyframe.hpp"
#include "motion/visual_motion.hpp"

namespace svslam {

struct LoopVerifierParams {
  int max_hamming = 64;               // bits of 256, a match farther than this is refused, 1..256
  double max_ratio = 0.85;            // best / second-best distance, (0, 1]
  int min_inliers = 25;               // pairs kept by the motion estimation, >= 6
  double min_inlier_fraction = 0.3;   // of the matches, [0, 1]
  double max_rms_mahalanobis = 3.0;   // of the inliers, > 0
  VisualMotionParams motion = defaultMotion();
  static VisualMotionParams defaultMotion();  // RANSAC on (seed 1), 300 iterations
  Status validate() const;
};

struct LoopConstraint {
  int query = -1;      // keyframe ids
  int candidate = -1;
  Eigen::Isometry3d T_query_candidate = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  int matches = 0;
  int inliers = 0;
  double rms_mahalanobis = 0;
  bool accepted = false;
  std::string reason;  // why not, when !accepted
};

class LoopVerifier {
 public:
  explicit LoopVerifier(const LoopVerifierParams& params);
  const Status& initStatus() const { return init_status_; }
  // Fills `out` (accepted or with the reason); returns an error only for invalid input.
  Status process(const Keyframe& query, const Keyframe& candidate, LoopConstraint& out);

 private:
  LoopVerifierParams params_;
  Status init_status_;
  VisualMotion motion_;
  std::vector<int> best_q_, best_c_;
  std::vector<PointPair> pairs_;
  VisualMotionResult result_;
};

// Mutual nearest neighbours between descriptor sets a and b with the distance and ratio tests:
// fills matches with (index in a, index in b), in increasing index of a.
void matchDescriptors(const std::vector<OrbDescriptor>& a, const std::vector<OrbDescriptor>& b,
                      int max_hamming, double max_ratio, std::vector<std::pair<int, int>>& matches);

}  // namespace svslam

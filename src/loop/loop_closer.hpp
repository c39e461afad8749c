#pragma once
// Loop closing (seed 000 "closing the loop", seed 002 sec 4): keyframes indexed by a binary
// bag-of-words, candidates geometrically verified, accepted by pairwise consistency with the
// odometry, and a pose graph over the keyframes re-solved after each accepted set of loops.
// Two halves, each for one thread and both deterministic given the same frames in order:
//
// LoopFrontEnd (the thread that sees every published frame with its image and dense disparity):
//   the keyframe rule (loop/keyframe.hpp), the keyframe's ORB points with 3D covariance, and the
//   covariance of the relative pose since the previous keyframe, compounded from the frame-to-
//   frame motion covariances of the front end (visual motion estimation, [dtheta, dt] of
//   T_cur_prev): with Z = T_kf_prev_frame (C) and the frame's motion M = T_cur_prev (C_M),
//     D = M^-1, C_D = J_inv C_M J_inv^T,   Z' = Z D,   C' = A_1 C A_1^T + A_2 C_D A_2^T
//   (loop/relative_pose.hpp's inversion and product Jacobians); a frame without a motion
//   estimate, or after frames this front end did not see, contributes the online estimate's
//   relative pose with gap_rot_sigma_rad / gap_trans_sigma_m; the first frame after a reset of
//   the estimator (a new world_epoch: its world frame starts again at the camera) contributes
//   the online relative pose between the two worlds' poses with kResetRotSigmaRad /
//   kResetTransSigmaM, i.e. nothing, and is made a keyframe (when it has the points); plus a floor of
//   odometry_floor_rot_rad^2 / odometry_floor_trans_m^2 per keyframe edge (the filter's
//   relative pose is not exactly the motion chain's, and a skipped frame adds nothing).
//
// LoopCloser (the back-end thread, one call per keyframe):
//  0. odometry edge from the previous keyframe: the motion chain, or (filter_edge_chi2 > 0) the
//     online estimate's relative pose when it agrees with the chain;
//  1. BoW vector of the keyframe (loop/binary_vocabulary.hpp); place query (loop/place_database
//     .hpp: inverted index, normalised score, islands, temporal consistency), then the keyframe
//     is added;
//  2. each returned candidate is verified (loop/loop_verifier.hpp); a verified constraint gives
//     the loop edge from = query, to = candidate, T_from_to = T_query_candidate, covariance;
//  3. PCM (loop/loop_consistency.hpp) over the verified constraints (the most recent
//     max_pcm_candidates) against the odometry edges (the keyframe poses chained from keyframe
//     0 by the motion chain, not the filter's poses, whose anchor closures jump): the maximum
//     clique is accepted when it has
//     at least min_consistent_loops members (a lone look-alike is never enough);
//  4. when the accepted set gained a member: the pose graph (loop/pose_graph.hpp; odometry edges
//     between consecutive keyframes, loop edges with the robust loss, the first keyframe of the
//     newest world_epoch fixed: keyframe 0 until the estimator is reset) is solved, warm-started
//     from the last solution (new keyframes chained on by odometry).
//  Resets (reconciled with the estimator's new world): the gauge is the current world's first
//  keyframe, so the current world's corrections stay drift corrections (the estimator's
//  feedback never moves it into an older world) and the earlier worlds' keyframes are solved
//  into the current world: tied by the uninformative edge alone they keep the shape of their
//  last solution, placed as the online estimates left them; once loops join the new world to
//  places seen before the reset (found, verified and PCM-checked as any other: two loops across
//  the reset must agree with each other through the odometry on both sides), the whole earlier
//  trajectory is moved into the current world.
//  correctedKeyframes() then holds T_world_kf after the last solution (the online estimates
//  before any); correctionAt() maps an online pose at any time into the corrected frame.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "core/status.hpp"
#include "loop/binary_vocabulary.hpp"
#include "loop/keyframe.hpp"
#include "loop/loop_consistency.hpp"
#include "loop/loop_verifier.hpp"
#include "loop/place_database.hpp"
#include "loop/pose_graph.hpp"
#include "stereo/dense_stereo.hpp"

namespace svslam {

struct LoopCloserParams {
  KeyframeParams keyframe;
  PlaceDatabaseParams place;
  LoopVerifierParams verify;
  LoopConsistencyParams consistency;
  PoseGraphParams graph;
  int min_consistent_loops = 2;       // PCM clique size before loops are used, >= 1
  int max_pcm_candidates = 64;        // verified constraints kept for PCM (newest), 2..1000
  double odometry_floor_rot_rad = 1e-4;   // per keyframe edge, rad, > 0
  double odometry_floor_trans_m = 2e-3;   // per keyframe edge, m, > 0
  // A frame without a motion estimate, or frames the front end did not see (skipped), enter
  // the chain as the online estimate's relative pose with these standard deviations, rad / m.
  double gap_rot_sigma_rad = 0.01;
  double gap_trans_sigma_m = 0.1;
  // After the first solution, the graph is re-solved when new loops were accepted and at least
  // this many keyframes arrived since the last solution (finish() solves what is pending), >= 1.
  int solve_every_keyframes = 5;
  // Bound of a solve: with more keyframes than this, only the newest this many move and the
  // older ones are held at their last solution (PoseGraph::optimize's first_free), so a solve
  // costs what a graph of this size costs however long the flight. 0 = the whole graph. >= 0.
  int max_solve_keyframes = 2000;
  // Odometry edge: the online estimate's relative pose between the two keyframes when it agrees
  // with the motion chain (Mahalanobis^2 under the chain's covariance below this), else the
  // chain (the filter jumped, e.g. when first-frame anchors came back: a jump inside an edge
  // would pin the drift). 0 = always the chain (default: docs/loop_closing.md has both). >= 0.
  double filter_edge_chi2 = 0.0;
  // Test hook (fault injection): this share of the verified loop constraints, drawn with a
  // generator seeded by wrong_loop_seed, is replaced by a wrong one: the same measurement
  // (relative pose and covariance) attached to another keyframe, drawn uniformly among those the
  // place database could have returned (a perceptual-aliasing false positive that passed
  // verification). 0 = off (default), at most 0.5.
  double wrong_loop_fraction = 0.0;
  std::uint32_t wrong_loop_seed = 1;
  Status validate() const;
};

// One frame as the front end sees it.
struct LoopFrameInput {
  std::int64_t frame = 0;
  std::int64_t t_ns = 0;
  int world_epoch = 0;  // the estimator's world (Keyframe::world_epoch); never decreases
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // online estimate
  bool motion_valid = false;  // the front end estimated T_cur_prev for this frame
  Eigen::Isometry3d T_cur_prev = Eigen::Isometry3d::Identity();
  Matrix6d motion_cov = Matrix6d::Zero();  // [dtheta, dt] of T_cur_prev
  Matrix6d pose_cov = Matrix6d::Zero();    // of T_world_cam, [dtheta, dt] (zero: unknown)
  ImageView<const std::uint8_t> left;      // rectified, calibration size
  const DisparityResult* dense = nullptr;  // its dense disparity (required for a keyframe)
};

class LoopFrontEnd {
 public:
  LoopFrontEnd(const LoopCloserParams& params, const StereoCalibration& calib);
  const Status& initStatus() const { return init_status_; }
  // True in `made` when the frame became keyframe `kf` (with the odometry covariance since the
  // previous keyframe in `odo_cov`, zero for the first). A frame without dense disparity or too
  // few points is not a keyframe (not an error).
  Status process(const LoopFrameInput& in, bool& made, Keyframe& kf, Matrix6d& odo_cov,
                 Eigen::Isometry3d& odo_T_prev_kf);
  int keyframes() const { return next_id_; }
  // The frame last given to process(): the last keyframe at or before it (-1: none yet) and
  // the motion chain from that keyframe to the frame (identity on a keyframe). A corrected
  // trajectory is T_corrected_kf * T_kf_frame for every frame (LoopCloser::correctedKeyframes).
  int lastKeyframe() const { return next_id_ - 1; }
  const Eigen::Isometry3d& chainFromLastKeyframe() const { return T_kf_frame_; }

 private:
  LoopCloserParams params_;
  Status init_status_;
  KeyframeSelector selector_;
  KeyframeBuilder builder_;
  int next_id_ = 0;
  Eigen::Isometry3d T_kf_frame_ = Eigen::Isometry3d::Identity();  // motion chain since the kf
  Matrix6d C_kf_frame_ = Matrix6d::Zero();
  std::int64_t last_frame_ = -1;
  Eigen::Isometry3d T_world_last_ = Eigen::Isometry3d::Identity();  // online, last frame seen
  int world_epoch_ = 0;
  std::int64_t world_since_t_ns_ = 0;
};

// The odometry edge across a reset of the estimator: standard deviations that make it carry
// no information next to any other edge (a pose graph needs the graph connected, not this
// edge's value), rad / m.
inline constexpr double kResetRotSigmaRad = 10.0;
inline constexpr double kResetTransSigmaM = 1e4;

struct AcceptedLoop {
  int query = -1, candidate = -1;  // keyframe ids
  std::int64_t query_frame = 0, candidate_frame = 0;  // their source frame indices
  int inliers = 0;
  Eigen::Isometry3d T_query_candidate = Eigen::Isometry3d::Identity();  // the measurement
  Matrix6d covariance = Matrix6d::Identity();                            // [dtheta, dt]
  double chi2_after = 0;  // whitened squared residual in the last solution
  bool injected = false;  // a wrong constraint made by the wrong_loop_fraction test hook
};

struct LoopCloserStats {
  int keyframes = 0;
  int queries_skipped = 0;       // place query skipped (no prior score)
  int candidates = 0;            // returned by the place database
  int verified = 0;              // passed geometric verification
  int rejected_verification = 0;
  int rejected_consistency = 0;  // verified, outside the accepted clique (at the last PCM run)
  int accepted = 0;              // loops in the accepted set
  int optimisations = 0;
  int last_optimisation_keyframes = 0;
  double last_max_correction_m = 0;  // largest keyframe translation change, last solution
  int chain_edges = 0;  // odometry edges taken from the motion chain (the filter disagreed)
  int injected_wrong = 0;           // wrong constraints made by the test hook
  int injected_wrong_accepted = 0;  // of those, in the accepted set
  int world_resets = 0;  // keyframes that began a new world_epoch (the estimator was reset)
};

class LoopCloser {
 public:
  // `vocabulary` outlives this object.
  LoopCloser(const LoopCloserParams& params, const BinaryVocabulary& vocabulary);
  const Status& initStatus() const { return init_status_; }
  // Back end: one keyframe (ids in order 0, 1, ...) and the odometry covariance of the edge
  // from the previous keyframe. `optimised` says whether the pose graph was re-solved.
  Status process(Keyframe&& kf, const Matrix6d& odo_cov, const Eigen::Isometry3d& odo_T_prev_kf,
                 bool& optimised);
  // After the last keyframe: solves the graph if accepted loops are not in the last solution.
  Status finish(bool& optimised);

  const std::vector<Keyframe>& keyframes() const { return keyframes_; }
  // T_world_kf after the last solution; keyframes since then are chained onto it by the motion
  // chain; the online estimates before any solution.
  const std::vector<Eigen::Isometry3d>& correctedKeyframes() const { return T_corrected_; }
  bool solved() const { return solved_; }  // the graph was solved at least once
  // Whether odometry edge k (keyframe k -> k + 1) came from the motion chain (false: from the
  // online estimate; also false for an edge not there yet).
  bool chainEdge(std::size_t k) const { return k < chain_edge_.size() && chain_edge_[k] != 0; }
  std::size_t edges() const { return chain_edge_.size(); }
  // Odometry edge k (keyframe k -> k + 1): T_k_(k+1) of the motion chain and its covariance.
  const Eigen::Isometry3d& odometryEdge(std::size_t k) const { return odo_T_[k]; }
  const Matrix6d& odometryCovariance(std::size_t k) const { return odo_cov_[k]; }
  // Online estimate of keyframe k when it was made.
  const Eigen::Isometry3d& onlineKeyframe(std::size_t k) const { return T_online_[k]; }
  // The correction C (T_corrected = C T_online, world frame) of the online pose at time t_ns:
  // C_k = T_corrected_kf_k T_online_kf_k^-1, interpolated between the keyframes around t_ns
  // (rotation slerp, translation lerp, by time; not across a reset: a time at or after the
  // newer world's start takes its first keyframe's correction); identity before any solution.
  // O(log N).
  Eigen::Isometry3d correctionAt(std::int64_t t_ns) const;
  const std::vector<AcceptedLoop>& acceptedLoops() const { return accepted_; }
  const LoopCloserStats& stats() const { return stats_; }
  std::size_t memoryBytes() const;

 private:
  Status runConsistency(bool& changed);
  Status optimise();
  // The wrong_loop_fraction test hook: maybe re-attach `lc` to a wrong keyframe.
  void injectWrongLoop(int query, LoopConstraint& lc);

  LoopCloserParams params_;
  const BinaryVocabulary& vocabulary_;
  Status init_status_;
  PlaceDatabase places_;
  LoopVerifier verifier_;
  LoopConsistency consistency_;
  PoseGraph graph_;
  std::vector<Keyframe> keyframes_;
  std::vector<Eigen::Isometry3d> T_online_;  // per keyframe
  std::vector<Matrix6d> odo_cov_;            // edge k: keyframe k -> k + 1
  std::vector<Eigen::Isometry3d> odo_T_;     // edge k: T_k_(k+1) of the motion chain
  std::vector<Eigen::Isometry3d> T_chain_;   // per keyframe: keyframe 0 then the odometry edges
  std::vector<std::uint8_t> chain_edge_;     // per edge: 1 = from the motion chain
  std::vector<Eigen::Isometry3d> T_corrected_;  // per keyframe (see correctedKeyframes)
  bool solved_ = false;
  std::vector<LoopConstraint> verified_;     // newest max_pcm_candidates
  std::vector<LoopConstraint> accepted_constraints_;
  std::vector<AcceptedLoop> accepted_;
  std::vector<PlaceCandidate> candidates_;
  LoopCloserStats stats_;
  std::mt19937 wrong_rng_;     // the wrong_loop_fraction test hook's draws
  std::vector<std::pair<int, int>> injected_;  // (query, candidate) of the injected constraints
  int gauge_ = 0;              // the fixed keyframe: the first of the newest world_epoch
  bool pending_ = false;       // accepted loops not yet in a solution
  int solved_keyframes_ = 0;   // keyframes at the last solution
};

}  // namespace svslam

#pragma once
// Stereo visual odometry: the tracking half of the front end and the visual motion estimation
// of seed 001 (sec. 3.3, 4.1) chained frame to frame, on the output of the stereo stage
// (odometry/stereo_stage.hpp: dense stereo, points, stereo matching, 3D points, ROIs).
//
// Per frame:
//  1. temporal matching of the stage's points against the previous frame's, around the
//     position predicted with the previous motion (constant velocity), each previous point
//     inside its ROI when the stage applied ROIs; on too few matches, retried with the identity
//     prediction and lost_search_radius_px. Before any motion has been measured (the first
//     pair, or after resetTracking) the identity is searched with lost_search_radius_px
//     straight away;
//     Re-prediction (params.repredict): when that prediction was the identity (first pair),
//     gave fewer than min_matches, or the median distance of the matched points from their
//     predicted positions exceeds repredict_px (a turn the constant velocity did not foresee):
//     (a) the rotation by coarse image alignment (motion/rotation_alignment.hpp) with the
//     constant-velocity translation predicts a second pass within lost_search_radius_px, kept
//     when it matches more; (b) a seeded RANSAC motion of the matches predicts a third pass at
//     the normal radius, kept when its own RANSAC motion has at least as many inliers. Only
//     then, still below min_matches, the retry. The motion of a re-predicted or retried frame
//     is estimated with seeded RANSAC (ransac_on_repredict);
//  2. visual motion estimation (motion/visual_motion.hpp) -> T_cur_prev and its covariance,
//     on the point pairs moved to the current disparity offset (both frames' points scaled by
//     disparityOffsetScale); then the offset estimate is updated with the frame
//     (motion/disparity_offset.hpp) and calibration() carries it for the next observations.
// Poses: T_first_cam = T_first_prev * T_cur_prev^-1 (left camera in the first left camera's
// frame, x right, y down, z forward). A frame whose motion cannot be estimated keeps the
// predicted motion and is reported as not tracked; the next frame continues from it.
// feedback() is what the stereo stage of the next frame needs (ROI tracking).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/executor.hpp"
#include "core/image.hpp"
#include "core/stage_observer.hpp"
#include "core/status.hpp"
#include "features/temporal_matcher.hpp"
#include "motion/rotation_alignment.hpp"
#include "motion/visual_motion.hpp"
#include "odometry/odometry_params.hpp"
#include "odometry/stereo_stage.hpp"
#include "stereo/reprojection.hpp"

namespace svslam {

struct OdometryFrameResult {
  int frame = 0;
  bool tracked = false;  // the motion was estimated from this frame's matches
  std::string failure;   // why not, when !tracked (empty for the first frame)
  Eigen::Isometry3d T_cur_prev = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();  // [rot, trans]
  Eigen::Isometry3d T_first_cam = Eigen::Isometry3d::Identity();
  int corners = 0;
  int stereo_points = 0;
  int temporal_matches = 0;
  int inliers = 0;
  // RMS over the inliers of the motion's residual Mahalanobis distance (VisualMotionResult):
  // about sqrt(3) when the point covariances match the data, larger when they are too small.
  double motion_rms_mahalanobis = 0;
  // The disparity offset after this frame (px) and this frame's own estimate of it.
  double disparity_offset_px = 0;
  DisparityOffsetFrame disparity_offset_frame;
  bool retried = false;
  bool repredicted = false;  // the matches are those of the guided second pass
  int rois = 0;             // ROI tracking: cluster regions used in this frame
  int roi_dropped = 0;      // corners outside every ROI and not in an unknown cell
  int unknown_corners = 0;  // corners kept in unknown cells
  StereoMatchStats stereo_stats;
  TemporalMatchStats temporal_stats;
};

class StereoOdometry {
 public:
  StereoOdometry(const StereoOdometryParams& params, const StereoCalibration& calib);
  ~StereoOdometry();
  const Status& initStatus() const { return init_status_; }

  // frontEnd() then estimateMotion() with every match. `observer` hears "temporal_match" and
  // "motion".
  Status process(ImageView<const std::uint8_t> left, const StereoStageOutput& stereo,
                 OdometryFrameResult& out, StageObserver* observer = nullptr);

  // The two halves of process(), for a caller (the SLAM filter) that needs to look at the
  // matches before the motion is estimated. frontEnd() takes the left image of the pair and the
  // stereo stage's output for it (from a StereoStage built with the same parameters, fed with
  // this object's feedback(); `stereo` must stay alive and unchanged until the next
  // frontEnd()), and fills points() and matches(); estimateMotion() uses the matches whose
  // `exclude[k]` is 0 (all when `exclude` is null) and updates the pose; the frame becomes the
  // previous one at the next frontEnd().
  Status frontEnd(ImageView<const std::uint8_t> left, const StereoStageOutput& stereo,
                  OdometryFrameResult& out, StageObserver* observer = nullptr);
  Status estimateMotion(const std::vector<std::uint8_t>* exclude, OdometryFrameResult& out,
                        StageObserver* observer = nullptr);
  // What the stereo stage of the next frame needs (after estimateMotion()).
  TrackingFeedback feedback() const;
  // After frontEnd() (until the next one): this frame's points, the previous frame's points,
  // and the temporal matches between them (indices into previousPoints() and points()).
  const std::vector<TrackPoint>& points() const { return cur_; }
  const std::vector<TrackPoint>& previousPoints() const { return prev_; }
  const std::vector<TemporalMatch>& matches() const { return matches_; }
  // This frame's left image (valid between frontEnd() and the next frontEnd()).
  ImageView<const std::uint8_t> currentLeft() const { return cur_left_.cview(); }
  // The 3D observation of a point of points() with a given 2D matching error (px): the
  // 8-neighbour combination of seed 001 sec 4.1 with dense stereo (0.5 or 1 px), else the
  // triangulation Jacobian with sigma_uv = matching_error_px. False when not observable.
  bool observe(const TrackPoint& p, double matching_error_px, StereoPoint& out) const;
  const StereoCalibration& calibration() const { return calib_; }
  const DisparityResult* denseDisparity() const { return disp_; }

  // Forgets the previous frame: the next frame starts a new segment at the current pose.
  void resetTracking();

 private:
  // Median over matches_ of |projected T_cur_prev * X_prev - matched point|, px (0 if none).
  double medianPredictionError(const Eigen::Isometry3d& T_cur_prev, const PinholeCamera& cam);
  // pairs_ = the 3D point pairs of `matches` whose exclude[k] is 0 (all when null).
  void fillPairs(const std::vector<TemporalMatch>& matches,
                 const std::vector<std::uint8_t>* exclude);
  Status repredict(ImageView<const std::uint8_t> left, const PinholeCamera& cam,
                   OdometryFrameResult& out);
  // Seeded RANSAC motion of `matches` into bootstrap_result_; its inlier count (0: failed).
  int bootstrap(const std::vector<TemporalMatch>& matches);
  StereoOdometryParams params_;
  StereoCalibration calib_;
  Status init_status_;
  const DisparityResult* disp_ = nullptr;  // the current frame's dense disparity, if any
  TemporalMatcher temporal_matcher_;
  VisualMotion motion_;
  VisualMotionResult motion_result_;  // reused every frame (its inlier flags keep capacity)
  VisualMotion bootstrap_motion_;     // RANSAC motion of the guided re-matching
  VisualMotionResult bootstrap_result_;
  DisparityOffsetEstimator disparity_offset_;
  std::vector<TemporalMatch> rematches_;
  TemporalMatchStats rematch_stats_;
  std::vector<double> errors_;  // scratch of medianPredictionError
  RotationAlignment rotation_alignment_;
  std::vector<Eigen::Matrix3d> starts_;
  std::vector<TrackPoint> prev_, cur_;
  std::vector<TemporalMatch> matches_;
  std::vector<PointPair> pairs_;
  ImageU8 prev_left_, cur_left_;
  bool in_frame_ = false;   // between frontEnd() and estimateMotion()
  bool completed_ = false;  // estimateMotion() done, not yet rolled over
  bool has_prev_ = false;
  int frame_ = 0;
  Eigen::Isometry3d last_motion_ = Eigen::Isometry3d::Identity();
  bool motion_known_ = false;  // last_motion_ was measured (not the initial identity)
  Eigen::Isometry3d T_first_cam_ = Eigen::Isometry3d::Identity();
};

}  // namespace svslam

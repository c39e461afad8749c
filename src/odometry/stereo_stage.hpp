#pragma once
// The per-frame stereo stage of the front end: everything computed from one rectified pair,
// so that a pipeline runs it on its own thread ahead of the estimator (seed 001 sec. 3.1, 3.2):
//  1. optional dense census stereo (the disparity prior and the 8-neighbour observation);
//  2. interest points in the left image (precise Harris / Shi-Tomasi with grid bucketing, or
//     the ORB of seed 002);
//  3. with clustered-feature ROI tracking (seed 004 sec 3.6): the previous frame's clusters of
//     3D points, moved by the estimator's predicted motion (TrackingFeedback), give left ROIs
//     (where corners are kept, and where each previous point is searched by the temporal
//     matcher) and right ROIs (which bound the disparity search); image cells outside every ROI
//     are unknown and keep corners down to threshold_rel * unknown_threshold_factor;
//  4. stereo matching of the points along the row (ZNCC, ratio, continuity, recovery);
//  5. 3D points with covariance (TrackPoint): from the dense 8-neighbourhood when dense is on,
//     otherwise from the triangulation Jacobian with sigma_d and match_sigma_px; points with a
//     disparity below min_disparity_px or farther than max_depth_m are left out;
//  6. with ROI tracking: clusters of these points, for the next frame's ROIs.
// Steps 1-2 need the pair alone; steps 3-6 need the estimator's feedback on the previous frame
// when ROI tracking is on (needsFeedback()), so a pipeline calls prepare() then, once that
// feedback is there, finish(). process() does both.
// An empty right view (the right camera lost: a source that delivers the left image alone)
// runs step 2 only: corners, no disparity, no stereo match, no point (the estimator flies on
// the left image, SlamSystem's camera-loss mode).
// The stage's state between frames is the previous frame's clusters and point count (ROI
// tracking only); a stage built from the same parameters gives the same output for the same
// sequence of pairs and feedbacks, whatever the executor.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "core/camera.hpp"
#include "core/executor.hpp"
#include "core/image.hpp"
#include "core/stage_observer.hpp"
#include "core/status.hpp"
#include "odometry/odometry_params.hpp"
#include "stereo/reprojection.hpp"

namespace svslam {

// What the estimator tells the stereo stage about the frame it has just processed, for the
// next frame's ROIs (used only with roi_tracking).
struct TrackingFeedback {
  bool has_previous = false;  // the next frame will be matched against the last one
  // The last frame's motion (left camera, current <- previous): the constant-velocity
  // prediction of the next one.
  Eigen::Isometry3d T_cur_prev = Eigen::Isometry3d::Identity();
};

// The product of the stereo stage for one pair. Buffers are reused from frame to frame.
struct StereoStageOutput {
  bool has_disparity = false;              // dense stereo ran (params.dense, a right view)
  bool left_only = false;                  // the right view was empty: corners only
  DisparityResult disparity;               // left-image disparity and sigma_d, px
  bool finished = false;                   // steps 3-6 ran
  std::vector<Eigen::Vector2f> corner_px;  // detected points (after the ROI filter), left, px
  std::vector<float> corner_resp;          // their detector responses
  float max_response = 0.0f;               // strongest corner response of the image (Harris)
  std::vector<StereoMatch> stereo;         // stereo matches of the points
  StereoMatchStats stereo_stats;
  std::vector<TrackPoint> points;  // step 5, left camera frame
  // ROI tracking (step 3).
  bool has_rois = false;    // ROIs were applied to this frame
  int rois = 0;             // cluster regions used
  int roi_dropped = 0;      // corners outside every ROI and not in an unknown cell
  int unknown_corners = 0;  // corners kept in unknown cells
  // One per point of the previous frame (has_rois): the left ROI [x0, y0, x1) x [y0, y1) px
  // its temporal match is searched in; all zero = no restriction.
  std::vector<Eigen::Vector4i> prev_regions;
  // Clears the per-frame content, keeping the capacity.
  void clear();
};

// The 3D observation (left camera frame, m, with covariance) of a stereo-matched pixel (u, v)
// of disparity d +- sigma_d px, with an image-plane matching error of matching_error_px: the
// 8-neighbour combination of seed 001 sec 4.1 over `dense` when given, else the triangulation
// Jacobian (d must be > 0 and the result finite). False when not observable. Used for the
// stage's points (step 5) and for the estimator's observations of them.
bool stereoObservation(const StereoCalibration& calib, const DisparityResult* dense, float u_px,
                       float v_px, float d_px, float sigma_d_px, double matching_error_px,
                       StereoPoint& out);

class StereoStage {
 public:
  // `params` are the front end's: detector, corners, orb, stereo_match, dense, dense_stereo,
  // roi_tracking, clusters, unknown_threshold_factor, match_sigma_px, min_disparity_px,
  // max_depth_m. Preallocates for the calibration's image size.
  StereoStage(const StereoOdometryParams& params, const StereoCalibration& calib);
  ~StereoStage();
  StereoStage(const StereoStage&) = delete;
  StereoStage& operator=(const StereoStage&) = delete;
  const Status& initStatus() const { return init_status_; }

  // Sizes a pooled output for this stage once, before its first frame (the dense images
  // allocated and touched, the point vectors reserved for the detector's bound), so that the
  // first pass of each pooled output costs no more than the later ones.
  void prepareOutput(StereoStageOutput& out) const;

  // Whether finish() reads the feedback (ROI tracking).
  bool needsFeedback() const { return params_.roi_tracking; }

  // Steps 1-2 on a pair of the calibration size. `observer` hears "dense_stereo" (when
  // enabled) and "detect".
  Status prepare(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                 StereoStageOutput& out, Executor& executor, StageObserver* observer = nullptr);
  // Steps 3-6 on the pair given to prepare(), with the estimator's feedback on the previous
  // frame. `observer` hears "stereo_match".
  Status finish(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                const TrackingFeedback& feedback, StereoStageOutput& out,
                StageObserver* observer = nullptr);
  // prepare() then finish().
  Status process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                 const TrackingFeedback& feedback, StereoStageOutput& out, Executor& executor,
                 StageObserver* observer = nullptr);

 private:
  // Step 3: filters out.corner_px by the ROIs of the previous clusters moved by T_cur_prev;
  // fills ranges_ and out.prev_regions.
  void applyRois(const Eigen::Isometry3d& T_cur_prev, StereoStageOutput& out);
  void buildPoints(StereoStageOutput& out) const;      // step 5
  Status clusterPoints(const StereoStageOutput& out);  // step 6

  StereoOdometryParams params_;
  StereoCalibration calib_;
  Status init_status_;
  CornerDetector detector_;
  std::unique_ptr<OrbExtractor> orb_;
  std::vector<OrbKeypoint> orb_kp_;
  std::vector<OrbDescriptor> orb_desc_;
  std::vector<Corner> corners_;
  StereoPointMatcher stereo_matcher_;
  std::unique_ptr<DenseStereo> dense_;
  std::size_t max_points_ = 0;  // bound of the points detected per frame
  // ROI tracking.
  std::unique_ptr<FeatureClusters> clusterer_;
  std::vector<Cluster> prev_clusters_, cur_clusters_;
  std::size_t prev_points_ = 0;  // points of the previous frame
  RoiSet roi_;
  std::vector<Eigen::Vector2i> ranges_;
  std::vector<Eigen::Vector3d> cluster_pts_;
  std::vector<float> cluster_quality_;
};

}  // namespace svslam

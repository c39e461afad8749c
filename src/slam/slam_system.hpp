#pragma once
// EKF SLAM over the stereo front end (seed 001 sec 4): the visual motion estimate of the
// non-landmark matches predicts the pose; landmarks observed in the frame update it.
//
// Per frame:
//  1. front end (StereoOdometry::frontEnd on the stereo stage's output: points with their 3D
//     position and covariance): temporal matches; tracks (candidate flags, track lengths) pass
//     from the previous frame's points to the current ones;
//  2. VME on the non-landmark, non-candidate matches only (prediction and update decorrelated):
//     a match is left out when its previous point is a candidate or lies within
//     landmark_exclusion_px of a landmark observed in the previous frame; prediction with
//     T_cur_prev and its covariance (when the VME fails: the previous motion with
//     lost_rot_sigma_rad / lost_trans_sigma_m, documented, not tuned per sequence);
//  3. observations: every landmark of the state predicted inside the image is searched by ZNCC
//     of its patch (taken at initialisation, never updated) over the left image, within
//     tolerance + 3 sigma of its predicted projection (sigma from the pose and landmark
//     covariances), then matched along the row in the right image around its predicted
//     disparity. A landmark observed in the previous frame uses the 0.5 px matching error of
//     consecutive frames and track_tolerance_px; one unseen for longer (re-perception, e.g.
//     after a loop) the 1 px error and reperception_tolerance_px (seed 001 sec 4.1), at most
//     max_reperceptions per frame, the best predicted first, searched first; then the tracked
//     landmarks, oldest first, up to max_observations per frame (bounded update cost). The
//     patch is warped to the predicted view (LandmarkManager::templateFor); the ZNCC peak is
//     refined to sub-pixel by Gauss-Newton on that template (refine_observations) and the
//     disparity by the stereo matcher's refinement. Chi-square gating;
//  4. landmark selection: about candidate_fraction of the new matches (points matched for the
//     first time) become candidates, the most precise first, in grid cells holding fewer than
//     max_per_cell landmarks and candidates (spread over the image); a candidate tracked over
//     candidate_min_frames consecutive frames whose stereo point is precise enough
//     (sqrt(trace cov) <= candidate_max_sigma_m) is initialised in the filter with the stereo
//     error alone (init_sigma_uv_px for the image-plane localisation);
//     The first frame defines the world frame (pose exact, zero covariance): its candidates
//     are chosen among all its points and, once they pass the same test, initialised from
//     their first-frame stereo point, patch and pose (EkfSlam::addLandmarkFromExactPose: no
//     cross covariance with the odometry, which never used them), so the map is anchored to
//     the true origin rather than to the pose the odometry has drifted to by then;
//  5. bounded cost: at most ekf.max_landmarks in the state; to make room, the landmark unseen
//     for the longest time (at least retire_unseen_frames) is retired: removed from the state,
//     kept in the map with its last estimate. A retired anchored landmark (step 4) predicted
//     inside the image is searched like a re-perception (at most max_reperceptions a frame, the
//     best predicted first) and, when found, put back into the state with its last estimate
//     and covariance and no cross covariance (EkfSlam::restoreLandmark), then observed with
//     the re-perception error: this is how a loop closes on the start's map. Leaving out the
//     correlations it had when retired assumes its error independent of the current state's:
//     exact for an anchor never updated (initialised from the exact first pose, independent of
//     the odometry), optimistic by what its updates tied it to the poses that observed it.
//     Only anchors come back (at most grid_cols x grid_rows x max_per_cell of them, a bounded
//     cost per frame): any other landmark was initialised from a drifted pose and its error
//     is mostly the error the current pose shares.
// Camera loss (seed 000 part 2, seed 003): a RightCameraMonitor classifies each right image
// (missing, flat, frozen). While it is unusable the frame is processed from the left image
// alone: the stereo stage's points are not used; the prediction is the filter's last motion
// (constant velocity) with mono_rot_sigma_rad and mono_trans_sigma_m + mono_trans_speed_fraction
// times the last translation (monocular mode's second frame, with no velocity yet:
// mono_start_rot_sigma_rad, mono_start_trans_sigma_m); the landmarks of the state
// are searched as in step 3 and observed by their bearing (EkfSlam::updateBearings, the same
// matching errors mono_track_error_px, mono_reperception_error_px) in two passes (active
// search): the landmarks tracked in the previous frame, best predicted first, an update, then
// the re-perceptions, predicted from the updated filter (smaller windows); left corners (the stereo stage's detections, strongest first, in grid cells
// short of landmarks) are tracked by ZNCC from frame to frame (their template follows them)
// and, once tracked over mono_candidate_min_frames with a parallax between their first and
// current bearing that BearingInitializer accepts, initialised from those two views (seed
// 003: cone densities fused by rejection sampling into a Gaussian, carried into the current
// camera frame and added with EkfSlam::addLandmark, so with its cross covariance with the
// pose). The metric scale is held by the landmarks already mapped. When the right image is
// usable again (after right_camera.resume_frames good frames) stereo resumes; its first frame
// is predicted like a mono frame (the odometry's previous frame is stale).
// Monocular mode (`--mode mono`, left_only): the whole flight from the left camera. The first
// pair is the scale source (the only use of the right image): its stereo points, the most
// precise first and at most max_per_cell per grid cell, are initialised at once from the exact
// first pose (EkfSlam::addLandmarkFromExactPose, anchored like step 4's), and every later frame
// is a mono frame as above (the right image is not looked at). Without a scale source
// (slam.mono_scale none) the right image is never looked at: the first frame is the reference
// (the world origin); up to mono_init_points of its corners are tracked by ZNCC (template
// following the corner, searched mono_search_px around its last position moved by the last
// frame's median flow) and at every frame TwoViewInitializer estimates the relative pose of
// the reference and the current frame (essential matrix or homography, chosen by score;
// triangulation, cheirality and parallax checks). Until it accepts one, the frame is
// `initializing` (the origin is published with an uninformative covariance); a reference not
// initialised after mono_init_max_frames frames, or left with too few tracks, is replaced by
// the current frame (the world origin moves to it). Once accepted, the unit is set so that the
// points' median depth is mono_init_depth_m; each point, with its linearised two-view
// covariance C = (sum_k (I - d_k d_k^T) / (sigma r_k)^2)^-1 (the two bearings d_k at range
// r_k, sigma = mono_bearing_sigma_px / f, poses exact), enters the filter anchored at the
// exact reference pose when sqrt(trace C) <= mono_init_max_rel_sigma times its depth, the most
// precise first, at most max_per_cell per cell; the filter is put at the current frame's pose
// with the monocular second frame's covariance (mono_start_*), and the next prediction is the
// mean motion since the reference. With slam.mono_scale altitude the same start waits for an
// altimeter reading (setAltitude) and scales the map so that the current camera's height above
// the plane fitted to the points (least squares) is the reading: a metric map without a stereo
// pair. Later frames are mono frames as above.
// Memory: every per-frame buffer is a member sized in the constructor (or grown once to the
// frame's stereo point count); the map's bookkeeping is preallocated for map_reserve landmarks.
// Once warm, a frame allocates nothing while the map holds fewer than map_reserve landmarks
// (in the state, anchored or retired; the retired map is bounded by the volume flown over).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <string>
#include <memory>
#include <vector>

#include "core/camera.hpp"
#include "core/executor.hpp"
#include "core/image.hpp"
#include "core/stage_observer.hpp"
#include "core/status.hpp"
#include "features/patch_similarity.hpp"
#include "odometry/stereo_odometry.hpp"
#include "slam/bearing_initializer.hpp"
#include "slam/ekf_slam.hpp"
#include "slam/estimator.hpp"
#include "slam/right_camera_monitor.hpp"
#include "slam/slam_params.hpp"
#include "slam/two_view_initializer.hpp"
#include "slam/landmark_manager.hpp"

namespace svslam {

class SlamSystem final : public Estimator {
 public:
  // left_only: monocular mode (above); otherwise stereo with the camera-loss fallback.
  SlamSystem(const SlamSystemParams& params, const StereoOdometryParams& odometry,
             const StereoCalibration& calib, bool left_only = false);
  const Status& initStatus() const override { return init_status_; }
  EstimatorOutputs outputs() const override { return {true, true}; }

  // Estimator::process; `observer` hears the odometry's stages and "ekf" (prediction,
  // observation, selection).
  Status process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                 const StereoStageOutput& stereo, SlamFrameResult& out, Executor& executor,
                 StageObserver* observer = nullptr) override;
  // After a mono frame the odometry's previous frame is stale: no prediction (the stereo stage
  // then detects over the whole image, no ROI from a stale motion).
  TrackingFeedback feedback() const override {
    return prev_mono_ ? TrackingFeedback{} : vo_.feedback();
  }

  void setAltitude(double altitude_m) override {
    if (std::isfinite(altitude_m) && altitude_m > 0.0) altitude_m_ = altitude_m;
  }

  // Every landmark ever initialised: in the state (current estimate) or retired.
  std::vector<MapLandmark> map() const override;
  // Estimator::applyLoopCorrection: the corrected position as a measurement
  // (EkfSlam::updatePosition), then the views the landmarks of the state were initialised from
  // turn with the pose (their template warps are relative to them). Position only: the filter
  // observes its attitude directly from landmarks spread over the view, better than a keyframe
  // rotation through one loop constraint; drift accumulates in the position (on the synthetic
  // 3-lap and look-alike flights the full pose measurement gave a larger online ATE,
  // docs/loop_closing.md).
  Status applyLoopCorrection(const Eigen::Isometry3d& C_new_old, const Matrix6d& cov_world,
                             Eigen::Isometry3d& moved) override;

 private:
  // process() without the calibration's covariance (added by process for every mode).
  Status processFrame(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                      const StereoStageOutput& stereo, SlamFrameResult& out, Executor& executor,
                      StageObserver* observer);
  // Whether (u, v) lies within landmark_exclusion_px of one of `landmarks_uv` (px).
  bool nearLandmark(const std::vector<Eigen::Vector2f>& landmarks_uv, float u, float v) const;
  void passTracks();
  // Searches the landmarks of the state in the current pair; fills obs_ / obs_uv_ (stereo) or,
  // when `right` is empty (mono frame), bobs_ / obs_uv_ with bearings. `pass` (mono frames'
  // active search): kAll searches as step 3 says; kFirst only the tracked landmarks, the best
  // predicted first; kRest the landmarks not yet observed this frame, as kAll, up to
  // max_observations - `already` observations.
  enum class SearchPass { kAll, kFirst, kRest };
  void searchLandmarks(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                       SlamFrameResult& out, SearchPass pass = SearchPass::kAll,
                       int already = 0);
  // A frame without the right image (camera loss); slam_mono.cpp.
  Status processMono(ImageView<const std::uint8_t> left, const StereoStageOutput& stereo,
                     SlamFrameResult& out, Executor& executor);
  // The constant-velocity prediction of mono frames (and of the first stereo frame after them).
  Status predictConstantVelocity();
  // Frame 0: the filter at the world origin with an exact pose, no anchor yet.
  Status startMap();
  // Monocular mode, frame 0: the map from the first pair's stereo points (vo_.points(), after
  // the front end), anchored at the exact first pose; fills out.added.
  void mapFirstPair(ImageView<const std::uint8_t> left, SlamFrameResult& out);
  // Monocular mode without a scale source, before the map exists: tracks the reference
  // frame's corners and tries the two-view start (slam_mono_start.cpp).
  Status processMonoStart(ImageView<const std::uint8_t> left, const StereoStageOutput& stereo,
                          SlamFrameResult& out);
  // The reference frame of the two-view start: the world origin, its corners to track.
  void startReference(ImageView<const std::uint8_t> left, const StereoStageOutput& stereo);
  void trackReference(ImageView<const std::uint8_t> left);
  // The map from an accepted two-view estimate (two_view_result_), the filter at the current
  // frame's pose; fills out.added.
  Status mapTwoView(ImageView<const std::uint8_t> left, SlamFrameResult& out);
  // diag(rot^2 I3, trans^2 I3), [dtheta (rad), dt (m)]: the motion covariance of a predicted
  // (not measured) frame.
  static Matrix6d diagonalMotionCov(double rot_sigma_rad, double trans_sigma_m);
  // The representativeness-grid cell (grid_cols x grid_rows over the image) of pixel (u, v).
  std::size_t gridCell(float u, float v) const;
  void applyObservations(SlamFrameResult& out, bool bearings);
  void trackMonoCandidates(ImageView<const std::uint8_t> left, SlamFrameResult& out);
  // Indices of the stereo stage's left corners, strongest response first (ties: ascending
  // index; all ties when the responses are absent), into `order`.
  static void strongestCornersFirst(const StereoStageOutput& stereo, std::vector<int>& order);
  void spawnMonoCandidates(ImageView<const std::uint8_t> left, const StereoStageOutput& stereo);
  void selectLandmarks(ImageView<const std::uint8_t> left, SlamFrameResult& out);
  // Records first-frame candidate p (stereo point and patch of `left`) as an anchor of `track`.
  void addAnchor(ImageView<const std::uint8_t> left, const TrackPoint& p, PointTrack& track);
  bool makeRoom(SlamFrameResult& out);
  // Brings retired anchored landmarks predicted in the current image and found there back into
  // the state (step 5); they are then observed as re-perceptions by searchLandmarks.
  // In a mono frame (`corners`: the left image's detected corners) a retired anchor is found
  // among those corners instead of the stereo points.
  void restoreAnchors(ImageView<const std::uint8_t> left, SlamFrameResult& out,
                      const std::vector<Eigen::Vector2f>* corners = nullptr);

  // A landmark of the state predicted inside the current image (searchLandmarks).
  struct SearchPrediction {
    int id = -1;
    double u = 0, v = 0, d = 0;                       // predicted pixel and disparity, px
    double sigma_px = 0;                              // of the projection, px
    double sigma_d = 0;                               // of the disparity, px
    Eigen::Vector3d z_cam = Eigen::Vector3d::Zero();  // predicted point, camera frame, m
    bool tracked = false;                             // observed in the previous frame
    int order = 0;  // position in the state: ties keep it (std::sort, no buffer)
  };

  // Projection of landmark m (world, m, covariance C) into the current left image from T_wc
  // with pose covariance P_pose: fills pr's pixel, disparity, camera point and sigmas; false
  // when the landmark is behind the camera or outside the image (minus the patch border).
  bool predictLandmark(const Eigen::Vector3d& m, const Eigen::Matrix3d& C,
                       const Eigen::Isometry3d& T_wc, const Matrix6d& P_pose,
                       SearchPrediction& pr) const;
  // Search radius around pr's pixel: tolerance + 3 sigma, at most reperception_max_radius_px.
  int searchRadius(const SearchPrediction& pr, double tolerance_px) const;
  // Warps the patch of landmark pr.id to its predicted view (LandmarkManager::templateFor) into
  // tmpl_, with its statistics; false when the warp fails or the template is flat.
  bool warpTemplate(const SearchPrediction& pr, const Eigen::Matrix3d& R_world_cam, PatchStats& ps);
  ImageView<const std::uint8_t> templateView() const {
    const int side = 2 * params_.patch_half_px + 1;
    return ImageView<const std::uint8_t>(tmpl_.data(), side, side, side);
  }
  // The current stereo point within r px of pr's pixel whose ZNCC against `patch` is highest
  // and at least reperception_min_zncc; -1 when none.
  // Whether one of `corners` within r px of pr's pixel matches `patch` (ZNCC above
  // reperception_min_zncc).
  bool nearCornerMatches(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> patch,
                         const PatchStats& ps, const SearchPrediction& pr, int r,
                         const std::vector<Eigen::Vector2f>& corners) const;
  int bestStereoPoint(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> patch,
                      const PatchStats& ps, const SearchPrediction& pr, int r) const;

  SlamSystemParams params_;
  StereoCalibration calib_;
  CalibrationConsider calib_consider_;
  DriftConsider drift_consider_;
  Status init_status_;
  StereoOdometry vo_;
  EkfSlam ekf_;
  LandmarkManager landmarks_;
  std::vector<PointTrack> prev_tracks_, cur_tracks_;
  // Step 3's right-image search of an observed landmark around its predicted disparity (one
  // row search per landmark on this thread; the stereo stage matches the detected points).
  StereoPointMatcher landmark_row_matcher_;
  std::vector<std::uint8_t> exclude_;
  std::vector<LandmarkObservation> obs_;
  std::vector<Eigen::Vector2f> obs_uv_;  // left image position of each observation
  std::vector<Eigen::Vector2f> prev_landmark_uv_, landmark_uv_;  // observed landmarks, px
  std::vector<ObservationResult> results_;
  std::vector<float> scores_;
  std::vector<SearchPrediction> preds_;          // landmarks predicted in the image, this frame
  std::vector<SearchPrediction> retired_preds_;  // retired anchors predicted in the image
  std::vector<int> fresh_;                       // points matched for the first time, this frame
  std::vector<std::uint8_t> tmpl_;               // warped landmark template
  std::vector<int> cell_count_;
  // First-frame candidates (step 4), indexed by PointTrack::anchor: the stereo point of that
  // frame (first left camera frame = world frame, m) and its appearance patch.
  std::vector<StereoPoint> anchor_points_;
  std::vector<std::uint8_t> anchor_patches_;  // (4 patch_half_px + 1)^2 bytes per anchor
  Eigen::Isometry3d anchor_pose_ = Eigen::Isometry3d::Identity();  // T_world_cam, first frame
  std::vector<int> anchored_ids_;  // ids of the landmarks initialised from anchors
  // Lost frames (relocalisation): keyframes kept while tracking is good; lost_ from a frame
  // without motion and with fewer than relocalisation.min_landmarks landmark observations until
  // relocalised, confirmed by the landmarks, or given up after max_lost_frames.
  std::unique_ptr<Relocaliser> reloc_;
  bool lost_ = false;
  int lost_frames_ = 0;
  // Step 3 of a stereo frame (retired anchors back, the landmarks searched) and the update.
  Status observeLandmarks(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                          SlamFrameResult& out, Executor& executor);
  Status relocaliseIfLost(ImageView<const std::uint8_t> left,
                          ImageView<const std::uint8_t> right, const StereoStageOutput& stereo,
                          SlamFrameResult& out, Executor& executor);
  // Camera loss.
  RightCameraMonitor right_monitor_;
  BearingInitializer<3> bearing_init_;
  std::vector<BearingObservation> bobs_;
  // A left corner tracked toward bearing-only initialisation: its first view (camera position
  // and bearing, world) and its last image position; its template (updated at every match) in
  // mono_patches_ at slot * (2 patch_half_px + 1)^2.
  struct MonoCandidate {
    bool alive = false;
    int first_frame = 0, frames = 0;
    std::uint64_t serial = 0;  // stream of the bearing sampler
    float u = 0, v = 0;        // last position, px
    Eigen::Vector3d o0_w = Eigen::Vector3d::Zero(), d0_w = Eigen::Vector3d::Zero();
    Eigen::Vector3d o_last_w = Eigen::Vector3d::Zero(), d_last_w = Eigen::Vector3d::Zero();
  };
  std::vector<MonoCandidate> mono_cands_;
  std::vector<std::uint8_t> mono_patches_;
  std::uint64_t mono_serial_ = 0;
  std::vector<double> depth_scratch_;
  std::vector<BearingView<3>> bearing_views_;
  // Two-view start (mono_scale none or altitude): the reference frame's corners, their pixel there
  // and now, templates at slot * (2 patch_half_px + 1)^2 of init_patches_.
  struct InitTrack {
    bool alive = false;
    float u0 = 0, v0 = 0;  // in the reference frame, px
    float u = 0, v = 0;    // last position, px
  };
  TwoViewInitializer two_view_;
  TwoViewResult two_view_result_;
  std::vector<InitTrack> init_tracks_;
  std::vector<std::uint8_t> init_patches_;
  std::vector<Eigen::Vector2d> init_x0_, init_x1_;  // normalised coordinates of the live tracks
  std::vector<int> init_index_;                     // their track index
  Eigen::Vector2f init_flow_ = Eigen::Vector2f::Zero();  // median flow of the last frame, px
  int reference_frame_ = 0;
  bool mono_started_ = false;  // the two-view start's map exists
  double altitude_m_ = 0;      // the last altimeter reading (0: none yet), m
  bool left_only_ = false;
  bool prev_mono_ = false;
  Eigen::Isometry3d prev_pose_ = Eigen::Isometry3d::Identity();    // filter pose, last frame
  Eigen::Isometry3d last_motion_ = Eigen::Isometry3d::Identity();  // T_cur_prev of the filter
  int frame_ = 0;
};

}  // namespace svslam

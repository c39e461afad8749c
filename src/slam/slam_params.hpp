#pragma once
// Parameters of the EKF SLAM system (slam/slam_system.hpp: the steps the comments refer to).
#include "core/status.hpp"
#include "slam/bearing_initializer.hpp"
#include "slam/calibration_consider.hpp"
#include "slam/drift_consider.hpp"
#include "slam/ekf_slam.hpp"
#include "slam/relocaliser.hpp"
#include "slam/right_camera_monitor.hpp"
#include "slam/two_view_initializer.hpp"

namespace svslam {

// What gives the monocular mode's map its scale (slam_system.hpp, "Monocular mode").
enum class MonoScaleSource {
  kFirstPair,  // the first stereo pair's points: a metric map
  kNone,       // the left camera alone from the first frame (two-view start): up to scale
  kAltitude,   // the same two-view start, its unit from an altimeter (Estimator::setAltitude):
               // the camera's height above the plane fitted to the first points is the
               // altitude; the start waits for a reading
};

struct SlamSystemParams {
  EkfSlamParams ekf;
  double candidate_fraction = 0.1;     // share of new matches made candidates, (0, 1]
  int candidate_min_frames = 3;        // consecutive frames tracked before initialisation, >= 2
  double candidate_max_sigma_m = 0.5;  // stability: sqrt(trace cov) of the stereo point, m, > 0
  int grid_cols = 8;                   // representativeness grid over the image, >= 1
  int grid_rows = 6;
  int max_per_cell = 3;                  // landmarks + candidates per cell and frame, >= 1
  double init_sigma_uv_px = 0.25;        // image-plane localisation at initialisation, px, > 0
  double track_matching_error_px = 0.5;  // consecutive frames (seed 001 sec 4.1)
  // re-perceiving after a loop (seed 001 sec 4.1: 1 px)
  double reperception_matching_error_px = 1.0;
  double track_tolerance_px = 1.5;              // consecutive frames (seed 001 sec 4.1: 1.5 px)
  double reperception_tolerance_px = 2.5;       // (seed 001 sec 4.1: about 2.5 px)
  int max_reperceptions = 10;                   // re-perception searches per frame, >= 0
  int max_observations = 60;  // landmark observations per frame, >= 1: seed 001 updates with
                              // every landmark matched; this only bounds the update cost
  double landmark_exclusion_px = 2.0;        // see step 2, px, >= 0
  double reperception_max_radius_px = 60.0;  // cap of the search radius, px
  float reperception_min_zncc = 0.8f;
  bool refine_observations = true;    // refine a tracked landmark's ZNCC position by
                                      // Gauss-Newton (subpixel_refine.hpp) instead of keeping
                                      // the parabola through the scores
  int patch_half_px = 5;              // appearance patch stored per landmark, 1..15
  int retire_unseen_frames = 2;       // a landmark unseen for fewer frames is never retired
  double lost_rot_sigma_rad = 0.035;  // prediction covariance when the VME fails
  double lost_trans_sigma_m = 0.5;
  // Flying on when the right camera dies (slam_system.hpp, "Camera loss"): the monitor of the
  // right image, the prediction while it is unusable (the filter's last motion, constant
  // velocity, with these sigmas per frame), and the bearing-only initialisation of new
  // landmarks from tracked left-image corners.
  RightCameraParams right_camera;
  // Constant-velocity prediction of a mono frame, per frame: rotation sigma (rad, > 0);
  // translation sigma mono_trans_sigma_m + mono_trans_speed_fraction |t_last| (m, >= 0 each,
  // sum > 0): a change of velocity within a frame is a fraction of the speed, plus a floor. The
  // defaults suit the rendered flights (config/mono_real_camera.yaml: real cameras).
  double mono_rot_sigma_rad = 0.01;
  double mono_trans_sigma_m = 0.2;
  double mono_trans_speed_fraction = 0.0;
  // Monocular mode's second frame, whose velocity nothing measured yet: rad, m, > 0.
  double mono_start_rot_sigma_rad = 0.05;
  double mono_start_trans_sigma_m = 1.0;
  BearingInitParams bearing_init;    // seed 003's initialisation (r_min_m, r_max_m, samples)
  int mono_max_candidates = 64;      // left corners tracked toward initialisation, [0, 4096]
  int mono_candidate_min_frames = 3;  // frames a corner is tracked before it may be initialised
  int mono_candidate_max_frames = 30;  // dropped when not initialised by then, >= min
  double mono_bearing_sigma_px = 1.0;  // angular error of a candidate's bearings, px, > 0
  double mono_search_px = 20.0;        // search radius of a candidate around its prediction, px
  // Matching errors of a bearing observation (px, > 0): tracked from the previous frame and
  // re-perceived. The defaults are the stereo frame's (rendered images); on real images no
  // right image checks the match and the whole pixel error goes into the bearing
  // (config/mono_real_camera.yaml doubles them).
  double mono_track_error_px = 0.5;
  double mono_reperception_error_px = 1.0;
  // Monocular mode's scale source and, with kNone, the two-view start: up to mono_init_points
  // corners of the reference frame are tracked (ZNCC, mono_search_px around their last
  // position moved by the median flow) and the relative pose of the reference and the current
  // frame is estimated at every frame (two_view: essential matrix or homography) until it is
  // accepted; a reference not initialised after mono_init_max_frames frames, or left with
  // fewer than two_view.min_inliers tracks, is replaced by the current frame. The map's unit:
  // the median depth of the first points is mono_init_depth_m (m, > 0; set it to the expected
  // scene depth so that the metre-valued sigmas keep their sense; the map is up to scale), or
  // with kAltitude the reading of the frame accepted (a metric map).
  MonoScaleSource mono_scale = MonoScaleSource::kFirstPair;
  TwoViewInitializerParams two_view;
  int mono_init_points = 300;       // [two_view.min_inliers, 4096]
  int mono_init_max_frames = 60;    // >= 2
  double mono_init_depth_m = 10.0;  // > 0
  double mono_init_max_rel_sigma = 0.1;  // a first point enters the map when its sqrt(trace cov)
                                         // is at most this fraction of its depth, (0, 1]
  int map_reserve = 4096;  // landmarks held at once (in the state, anchored, or in the retired
                           // map) whose storage is preallocated (about 0.7 kB each),
                           // >= ekf.max_landmarks; beyond it the storage grows by doubling
  // A landmark retired from the state for good is kept in the map at most one per cubic voxel
  // of this side (the best localised), m, > 0: the map is bounded by the volume it covers, not
  // by the flight time (slam/retired_landmark_map.hpp).
  double map_voxel_m = 0.25;
  // Relocalisation after a real loss (slam/relocaliser.hpp; SlamSystem "Lost frames"): keyframes
  // kept while tracking is good, a lost frame's pose found against them. Stereo ekf mode.
  RelocaliserParams relocalisation;
  // Uncertainty of the rig's calibration, carried into the published pose covariance
  // (slam/calibration_consider.hpp; SlamFrameResult::pose_cov_consider). A calibration
  // marked exact (StereoCalibration::exact: rendered sources) adds nothing whatever these say.
  CalibrationConsiderParams calibration_uncertainty{1.0, 0.002};
  // The odometry's rotational drift per metre travelled, carried into the published pose
  // covariance beside the calibration's (slam/drift_consider.hpp). The default is svslam's
  // drift on kitti_odometry_seq_a (devkit r_err 0.025 deg/m = sqrt(3) x 0.25 mrad/m;
  // docs/slam.md "Drift in the published covariance"). Nothing for exact calibrations.
  DriftConsiderParams drift_uncertainty{0.25e-3};
  Status validate() const;
};

}  // namespace svslam

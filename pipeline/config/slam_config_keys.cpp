// The keys of the slam section (SlamSystemParams and its EkfSlamParams): field, unit, range and
// doc of each, once.
#include "pipeline/config/config_keys.hpp"

namespace svslam::config {

namespace {
inline constexpr EnumNames<MonoScaleSource, 3> kMonoScaleNames{
    {{"first_pair", MonoScaleSource::kFirstPair},
     {"none", MonoScaleSource::kNone},
     {"altitude", MonoScaleSource::kAltitude}}};
}  // namespace

ConfigSection slamConfigSection() {
  ConfigSection s{"slam", "EKF SLAM (src/slam/slam_system.hpp, src/slam/ekf_slam.hpp)", {}};
  s.keys = {
      number("max_landmarks", SVSLAM_FIELD(slam.ekf.max_landmarks), 1, 3000, "",
             "landmarks in the filter state (older unseen ones retire to the map); update cost "
             "~ 3 k (n^2 + 2 n m), n = 6 + 3 max_landmarks"),
      number("max_batch_observations", SVSLAM_FIELD(slam.ekf.max_batch_observations), 1, 1000, "",
             "observations stacked in one update (m = 3 max_batch_observations)"),
      number("gate_chi2", SVSLAM_FIELD(slam.ekf.gate_chi2), 0.1, 1000, "",
             "Mahalanobis d^2 gate, chi-square 3 dof (99 %)"),
      flag("joseph_form", SVSLAM_FIELD(slam.ekf.joseph_form),
           "Joseph-form covariance update; false: optimal-gain form"),
      number("candidate_fraction", SVSLAM_FIELD(slam.candidate_fraction), 0.001, 1, "",
             "share of the new matches made candidate landmarks"),
      number("candidate_min_frames", SVSLAM_FIELD(slam.candidate_min_frames), 2, 1000, "",
             "consecutive frames a candidate is tracked before initialisation"),
      number("candidate_max_sigma_m", SVSLAM_FIELD(slam.candidate_max_sigma_m), 1e-6, 1e6, "m",
             "stability: sqrt(trace cov) of the candidate's stereo point"),
      number("grid_cols", SVSLAM_FIELD(slam.grid_cols), 1, 256, "",
             "representativeness grid columns over the image"),
      number("grid_rows", SVSLAM_FIELD(slam.grid_rows), 1, 256, "", "representativeness grid rows"),
      number("max_per_cell", SVSLAM_FIELD(slam.max_per_cell), 1, 10000, "",
             "landmarks + candidates per grid cell and frame"),
      number("init_sigma_uv_px", SVSLAM_FIELD(slam.init_sigma_uv_px), 0.01, 10, "px",
             "image-plane localisation of a new landmark"),
      number("track_matching_error_px", SVSLAM_FIELD(slam.track_matching_error_px), 0.01, 10, "px",
             "matching error between consecutive frames (seed 001 sec 4.1)"),
      number("reperception_matching_error_px", SVSLAM_FIELD(slam.reperception_matching_error_px),
             0.01, 10, "px", "matching error when re-perceiving after a long loop"),
      number("track_tolerance_px", SVSLAM_FIELD(slam.track_tolerance_px), 0.01, 100, "px",
             "search tolerance between consecutive frames"),
      number("reperception_tolerance_px", SVSLAM_FIELD(slam.reperception_tolerance_px), 0.01, 100,
             "px", "search tolerance when re-perceiving"),
      number("max_reperceptions", SVSLAM_FIELD(slam.max_reperceptions), 0, 10000, "",
             "re-perception searches per frame (searched first)"),
      number("max_observations", SVSLAM_FIELD(slam.max_observations), 1, 10000, "",
             "landmark observations per frame (bounds the EKF update cost and the latency)"),
      number("landmark_exclusion_px", SVSLAM_FIELD(slam.landmark_exclusion_px), 0, 100, "px",
             "matches this close to a landmark stay out of the VME"),
      number("reperception_max_radius_px", SVSLAM_FIELD(slam.reperception_max_radius_px), 0.01,
             1000, "px", "cap of the re-perception search radius"),
      number("reperception_min_zncc", SVSLAM_FIELD(slam.reperception_min_zncc), -1, 1, "",
             "acceptance threshold of a re-perceived landmark"),
      flag("refine_observations", SVSLAM_FIELD(slam.refine_observations),
           "Gauss-Newton sub-pixel position of a tracked landmark (else the ZNCC parabola)"),
      number("patch_half_px", SVSLAM_FIELD(slam.patch_half_px), 1, 15, "px",
             "appearance patch (2h+1)^2 kept per landmark"),
      number("map_voxel_m", SVSLAM_FIELD(slam.map_voxel_m), 1e-4, 1e6, "m",
             "a landmark retired from the state stays in the map at most one per voxel of this "
             "side (the best localised): the map grows with the volume seen, not the flight time"),
      number("retire_unseen_frames", SVSLAM_FIELD(slam.retire_unseen_frames), 1, 100000, "",
             "a landmark unseen for fewer frames is never retired"),
      number("lost_rot_sigma_rad", SVSLAM_FIELD(slam.lost_rot_sigma_rad), 1e-6, 10, "rad",
             "prediction covariance (rotation) when the VME fails"),
      number("lost_trans_sigma_m", SVSLAM_FIELD(slam.lost_trans_sigma_m), 1e-6, 1000, "m",
             "prediction covariance (translation) when the VME fails"),
      flag("relocalise", SVSLAM_FIELD(slam.relocalisation.enabled),
           "keep keyframes while tracking is good and find a lost frame's pose against them "
           "(ekf mode; needs dense_stereo.enabled; docs/slam.md)"),
      number("relocalise_keyframes", SVSLAM_FIELD(slam.relocalisation.max_keyframes), 1, 100000,
             "", "keyframes kept for relocalisation (a ring: the oldest replaced)"),
      number("relocalise_pending_keyframes",
             SVSLAM_FIELD(slam.relocalisation.pending_keyframes), 0, 100, "",
             "newest keyframes kept as image and disparity and built (ORB, 44-167 ms each) only "
             "when a lost frame needs them; 0 builds each keyframe on the estimator's thread"),
      number("relocalise_builds_per_frame",
             SVSLAM_FIELD(slam.relocalisation.max_builds_per_frame), 1, 100, "",
             "pending keyframes built per lost frame at most (the nearest first)"),
      number("relocalise_candidates", SVSLAM_FIELD(slam.relocalisation.max_candidates), 1, 1000,
             "", "keyframes verified per lost frame, nearest the predicted position first"),
      number("relocalise_min_landmarks", SVSLAM_FIELD(slam.relocalisation.min_landmarks), 0,
             10000, "",
             "a frame without motion and with fewer landmark observations than this is lost"),
      number("relocalise_max_lost_frames", SVSLAM_FIELD(slam.relocalisation.max_lost_frames), 1,
             100000, "",
             "lost frames with points whose relocalisation failed before the loss is given up"),
      number("relocalise_min_inliers", SVSLAM_FIELD(slam.relocalisation.verify.min_inliers), 6,
             2000, "", "inliers of the 3D-3D motion against a keyframe to accept a pose"),
      number("calibration_sigma_principal_point_px",
             SVSLAM_FIELD(slam.calibration_uncertainty.sigma_principal_point_px), 0, 100, "px",
             "standard deviation of the left camera's principal point (svslam calibrate reports "
             "it): its error turns the camera frame, so the path; added to the published pose "
             "covariance (not for rendered sources, whose calibration is exact)"),
      number("calibration_sigma_scale", SVSLAM_FIELD(slam.calibration_uncertainty.sigma_scale), 0,
             0.5, "", "relative standard deviation of the stereo depth scale (baseline, focal "
             "length): scales the path; added to the published pose covariance"),
      number("drift_sigma_rotation_rad_per_m",
             SVSLAM_FIELD(slam.drift_uncertainty.sigma_rotation_rad_per_m), 0, 0.1, "rad/m",
             "standard deviation of the odometry's rotational drift per metre travelled, about "
             "each camera axis (0 = none): grows the published attitude and position "
             "covariance with the path (not for rendered sources)"),
      flag("right_camera_check", SVSLAM_FIELD(slam.right_camera.enabled),
           "watch the right image (missing, flat, frozen) and fly on the left one alone while "
           "it is unusable (bearing-only SLAM)"),
      number("right_camera_min_stddev", SVSLAM_FIELD(slam.right_camera.min_stddev), 0, 255,
             "grey levels", "a right image whose sampled standard deviation is lower is flat"),
      number("right_camera_resume_frames", SVSLAM_FIELD(slam.right_camera.resume_frames), 1, 1000,
             "", "consecutive usable right images before stereo resumes"),
      number("mono_rot_sigma_rad", SVSLAM_FIELD(slam.mono_rot_sigma_rad), 1e-6, 10, "rad",
             "prediction sigma (rotation, per frame) of a frame without the right camera "
             "(constant velocity)"),
      number("mono_trans_sigma_m", SVSLAM_FIELD(slam.mono_trans_sigma_m), 0, 1000, "m",
             "prediction sigma (translation, per frame) of a frame without the right camera: "
             "this floor plus mono_trans_speed_fraction times the last frame's translation"),
      number("mono_trans_speed_fraction", SVSLAM_FIELD(slam.mono_trans_speed_fraction), 0, 100,
             "", "part of the prediction's translation sigma proportional to the speed"),
      number("mono_start_rot_sigma_rad", SVSLAM_FIELD(slam.mono_start_rot_sigma_rad), 1e-6, 10,
             "rad", "mode mono: prediction sigma (rotation) of the second frame (no velocity yet)"),
      number("mono_start_trans_sigma_m", SVSLAM_FIELD(slam.mono_start_trans_sigma_m), 1e-6, 1000,
             "m", "mode mono: prediction sigma (translation) of the second frame"),
      number("bearing_gate_chi2", SVSLAM_FIELD(slam.ekf.bearing_gate_chi2), 0.1, 1000, "",
             "Mahalanobis d^2 gate of a bearing observation, chi-square 2 dof (99 %)"),
      number("bearing_r_min_m", SVSLAM_FIELD(slam.bearing_init.r_min_m), 1e-3, 1e5, "m",
             "vision range of the bearing-only initialisation (seed 003), lower bound"),
      number("bearing_r_max_m", SVSLAM_FIELD(slam.bearing_init.r_max_m), 1e-3, 1e6, "m",
             "vision range of the bearing-only initialisation, upper bound (> bearing_r_min_m)"),
      number("bearing_samples", SVSLAM_FIELD(slam.bearing_init.num_samples), 10, 1000000, "",
             "rejection samples the initial Gaussian of a bearing-only landmark is fitted to"),
      number("bearing_min_parallax_sigmas", SVSLAM_FIELD(slam.bearing_init.min_parallax_sigmas),
             0, 1000, "", "a bearing-only landmark waits until its two bearings differ by this "
                          "many sigmas"),
      number("mono_max_candidates", SVSLAM_FIELD(slam.mono_max_candidates), 0, 4096, "",
             "left corners tracked toward bearing-only initialisation"),
      number("mono_candidate_min_frames", SVSLAM_FIELD(slam.mono_candidate_min_frames), 2, 1000,
             "", "frames a corner is tracked before it may be initialised"),
      number("mono_candidate_max_frames", SVSLAM_FIELD(slam.mono_candidate_max_frames), 2, 100000,
             "", "a corner not initialised after this many frames is dropped"),
      number("mono_bearing_sigma_px", SVSLAM_FIELD(slam.mono_bearing_sigma_px), 0.01, 100, "px",
             "angular error of a tracked corner's bearings"),
      number("mono_search_px", SVSLAM_FIELD(slam.mono_search_px), 1, 1000, "px",
             "search radius of a tracked corner around its prediction"),
      number("mono_track_error_px", SVSLAM_FIELD(slam.mono_track_error_px), 1e-3, 100, "px",
             "matching error of a bearing observation of a landmark tracked from the previous "
             "frame (no right image checks it)"),
      choice("mono_scale", SVSLAM_FIELD(slam.mono_scale), kMonoScaleNames,
             "mode mono: the scale source; first_pair: the first stereo pair (a metric map); "
             "none: the left camera alone from the first frame, a two-view start (a map up to "
             "scale, its unit set by mono_init_depth_m); altitude: the same start, its unit from "
             "the altimeter on lcm.altitude_channel (a metric map; needs lcm.enabled)"),
      number("mono_init_points", SVSLAM_FIELD(slam.mono_init_points), 8, 4096, "",
             "mono_scale none: corners of the reference frame tracked toward the two-view start "
             "(>= two_view_min_inliers)"),
      number("mono_init_max_frames", SVSLAM_FIELD(slam.mono_init_max_frames), 2, 100000, "",
             "mono_scale none: a reference frame not initialised after this many frames is "
             "replaced by the current one"),
      number("mono_init_depth_m", SVSLAM_FIELD(slam.mono_init_depth_m), 1e-3, 1e6, "m",
             "mono_scale none: the median depth given to the first map's points (the map's unit; "
             "the expected scene depth keeps the metre-valued sigmas meaningful)"),
      number("mono_init_max_rel_sigma", SVSLAM_FIELD(slam.mono_init_max_rel_sigma), 1e-4, 1, "",
             "mono_scale none: a first point enters the map when sqrt(trace cov) is at most this "
             "fraction of its depth"),
      number("two_view_ransac_iterations", SVSLAM_FIELD(slam.two_view.ransac_iterations), 1,
             100000, "", "two-view start: RANSAC hypotheses per model (essential, homography)"),
      number("two_view_inlier_px", SVSLAM_FIELD(slam.two_view.inlier_threshold_px), 0.01, 100,
             "px", "two-view start: residual sigma of the inlier tests"),
      number("two_view_min_inliers", SVSLAM_FIELD(slam.two_view.min_inliers), 8, 4096, "",
             "two-view start: triangulated inliers needed"),
      number("two_view_min_parallax_deg", SVSLAM_FIELD(slam.two_view.min_parallax_deg), 0.01, 90,
             "deg", "two-view start: median triangulation angle needed"),
      number("mono_reperception_error_px", SVSLAM_FIELD(slam.mono_reperception_error_px), 1e-3,
             100, "px", "matching error of a re-perceived landmark's bearing observation"),
  };
  return s;
}

}  // namespace svslam::config

// The keys of the slam section (SlamSystemParams and its EkfSlamParams): field, unit, range and
// doc of each, once.
#include "pipeline/config/config_keys.hpp"

namespace svslam::config {

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
  };
  return s;
}

}  // namespace svslam::config

// The keys of the top level and of the front end (detector, orb, stereo_match, temporal_match,
// motion, dense_stereo, clusters, odometry): the field, unit, range and doc of each, once.
// Defaults are the struct defaults of RunConfig and the src/ parameter structs.
#include "pipeline/config/config_keys.hpp"

namespace svslam::config {
namespace {

const EnumNames<PointDetector, 2> kDetectorNames{
    {{"corners", PointDetector::kCorners}, {"orb", PointDetector::kOrb}}};
const EnumNames<CornerResponse, 2> kResponseNames{
    {{"harris", CornerResponse::kHarris}, {"shi-tomasi", CornerResponse::kShiTomasi}}};
const EnumNames<StereoSigmaMode, 2> kSigmaModeNames{
    {{"curvature", StereoSigmaMode::kCurvature}, {"fixed", StereoSigmaMode::kFixed}}};
const EnumNames<SubpixelMethod, 2> kSubpixelNames{
    {{"parabola", SubpixelMethod::kParabola}, {"refine", SubpixelMethod::kRefine}}};
const EnumNames<MatchingCost, 2> kCostNames{
    {{toString(MatchingCost::kCensus), MatchingCost::kCensus},
     {toString(MatchingCost::kSad), MatchingCost::kSad}}};
const EnumNames<RoiRadius, 2> kRoiRadiusNames{
    {{"sphere-bound", RoiRadius::kSphereBound}, {"farthest-point", RoiRadius::kFarthestPoint}}};

ConfigSection topLevel() {
  ConfigSection s{"", "", {}};
  s.keys = {
      text("source", SVSLAM_FIELD(source),
           "kitti:DIR | euroc:DIR | synthetic[:key=value,...] | v4l2:... | libcamera:... | "
           "lcm:CHANNEL"),
      number("max_frames", SVSLAM_FIELD(max_frames), 0, 100000000, "",
             "stop after this many frames; 0 = whole sequence"),
      number("threads", SVSLAM_FIELD(threads), 1, 256, "",
             "worker threads of the stages that split work (dense stereo stripes)"),
      unsignedInt("seed", SVSLAM_FIELD(seed),
                  "seeds every random choice (RANSAC); same input + config = same output"),
      choice("mode", SVSLAM_FIELD(mode), kEstimatorModeNames,
             "ekf: EKF SLAM filter (seed 001 sec 4); vo: pure visual odometry; mono: the EKF from "
             "the left camera alone (bearing observations), the first stereo pair gives the scale"),
  };
  return s;
}

ConfigSection detector() {
  ConfigSection s{"detector", "interest points (src/features/corner_detector.hpp)", {}};
  s.keys = {
      choice("kind", SVSLAM_FIELD(odometry.detector), kDetectorNames,
             "corners (keys below) or the improved ORB of seed 002 (keys under orb:)"),
      choice("response", SVSLAM_FIELD(odometry.corners.response), kResponseNames,
             "precise Harris (derivative-of-Gaussian) or Shi-Tomasi"),
      number("sigma_d_px", SVSLAM_FIELD(odometry.corners.sigma_d_px), 0.5, 5, "px",
             "derivative scale"),
      number("sigma_i_px", SVSLAM_FIELD(odometry.corners.sigma_i_px), 0.5, 10, "px",
             "integration scale of the structure tensor"),
      number("harris_k", SVSLAM_FIELD(odometry.corners.harris_k), 0.01, 0.25, "",
             "Harris response det - k trace^2"),
      number("threshold_rel", SVSLAM_FIELD(odometry.corners.threshold_rel), 0, 1, "",
             "minimum response relative to the image's strongest"),
      number("grid_cols", SVSLAM_FIELD(odometry.corners.grid_cols), 1, 256, "",
             "bucketing grid columns: each cell keeps its strongest corners"),
      number("grid_rows", SVSLAM_FIELD(odometry.corners.grid_rows), 1, 256, "",
             "bucketing grid rows"),
      number("max_per_cell", SVSLAM_FIELD(odometry.corners.max_per_cell), 1, 10000, "",
             "corners kept per grid cell"),
      number("border_px", SVSLAM_FIELD(odometry.corners.border_px), 1, 200, "px",
             "no corner this close to the image border"),
  };
  return s;
}

ConfigSection orb() {
  ConfigSection s{"orb", "src/features/orb_extractor.hpp (when detector.kind is orb)", {}};
  s.keys = {
      number("num_octaves", SVSLAM_FIELD(odometry.orb.num_octaves), 1, 4, "",
             "octaves of the pyramid, an ordinary and an intermediate layer each"),
      number("fast_threshold", SVSLAM_FIELD(odometry.orb.fast_threshold), 1, 254, "grey levels",
             "FAST 9-16 threshold, same on every layer"),
      number("orientation_radius_px", SVSLAM_FIELD(odometry.orb.orientation_radius_px), 3, 15, "px",
             "radius of the intensity-centroid disc (pixels of the layer)"),
      number("blur_sigma_px", SVSLAM_FIELD(odometry.orb.blur_sigma_px), 0.5, 4, "px",
             "Gaussian before the BRIEF tests (pixels of the layer)"),
      number("angle_step_deg", SVSLAM_FIELD(odometry.orb.angle_step_deg), 1, 45, "deg",
             "steering quantisation of the pattern, divides 360"),
      unsignedInt("pattern_seed", SVSLAM_FIELD(odometry.orb.pattern_seed),
                  "seeds the 256 BRIEF point pairs"),
      number("grid_cols", SVSLAM_FIELD(odometry.orb.grid_cols), 1, 256, "",
             "bucketing grid columns"),
      number("grid_rows", SVSLAM_FIELD(odometry.orb.grid_rows), 1, 256, "", "bucketing grid rows"),
      number("max_per_cell", SVSLAM_FIELD(odometry.orb.max_per_cell), 1, 10000, "",
             "key points kept per grid cell"),
  };
  return s;
}

ConfigSection stereoMatch() {
  ConfigSection s{"stereo_match",
                  "left-right matching of the points (src/features/stereo_point_matcher.hpp)",
                  {}};
  s.keys = {
      number("patch_half_px", SVSLAM_FIELD(odometry.stereo_match.patch_half_px), 1, 15, "px",
             "ZNCC patch (2h+1)^2"),
      number("min_disp_px", SVSLAM_FIELD(odometry.stereo_match.min_disp_px), 0, 1024, "px",
             "disparities searched along the row: [min, max)"),
      number("max_disp_px", SVSLAM_FIELD(odometry.stereo_match.max_disp_px), 1, 1024, "px",
             "one past the largest disparity searched, > min_disp_px"),
      number("min_zncc", SVSLAM_FIELD(odometry.stereo_match.min_zncc), -1, 1, "",
             "acceptance threshold"),
      number("ratio", SVSLAM_FIELD(odometry.stereo_match.ratio), 0.01, 1, "",
             "ratio test on 1 - zncc (best vs second best at |d - d_best| > 1)"),
      number("ratio_floor", SVSLAM_FIELD(odometry.stereo_match.ratio_floor), 0, 1, "",
             "1 - zncc of the best taken as at least this (repeated texture)"),
      number("prior_radius_px", SVSLAM_FIELD(odometry.stereo_match.prior_radius_px), 1, 64, "px",
             "search half-range around the dense disparity, when dense is on"),
      flag("continuity_check", SVSLAM_FIELD(odometry.stereo_match.continuity_check),
           "seed 002 eq. 10: 3 nearest neighbours within continuity_threshold_px"),
      number("continuity_threshold_px", SVSLAM_FIELD(odometry.stereo_match.continuity_threshold_px),
             0.01, 1024, "px", "d_th of seed 002 eq. 10"),
      flag("recovery", SVSLAM_FIELD(odometry.stereo_match.recovery),
           "seed 002 eq. 11: Delaunay-based recovery of rejected matches"),
      number("recovery_dist_th_px", SVSLAM_FIELD(odometry.stereo_match.recovery_dist_th_px), 0.01,
             100, "px", "Dist_th of seed 002 eq. 11"),
      number("recovery_margin_px", SVSLAM_FIELD(odometry.stereo_match.recovery_margin_px), 0, 64,
             "px", "widening of the triangle's disparity span"),
      choice("sigma_mode", SVSLAM_FIELD(odometry.stereo_match.sigma_mode), kSigmaModeNames,
             "sigma_d of a match: calibrated table of the ZNCC peak curvature, or sigma_d_px"),
      number("sigma_d_px", SVSLAM_FIELD(odometry.stereo_match.sigma_d_px), 0.01, 10, "px",
             "fixed mode: disparity standard deviation of every match"),
      number("min_sigma_d_px", SVSLAM_FIELD(odometry.stereo_match.min_sigma_d_px), 0, 10, "px",
             "curvature mode: floor of the calibrated sigma_d"),
      choice("subpixel", SVSLAM_FIELD(odometry.stereo_match.subpixel), kSubpixelNames,
             "parabola through the ZNCC scores, or then Gauss-Newton on the patch (Lanczos)"),
      number("refine_iterations", SVSLAM_FIELD(odometry.stereo_match.refine.max_iterations), 1, 50,
             "", "refine: Gauss-Newton iterations at most"),
  };
  return s;
}

ConfigSection temporalMatch() {
  ConfigSection s{
      "temporal_match", "frame-to-frame matching (src/features/temporal_matcher.hpp)", {}};
  s.keys = {
      number("patch_half_px", SVSLAM_FIELD(odometry.temporal_match.patch_half_px), 1, 15, "px",
             "ZNCC patch (2h+1)^2"),
      number("search_radius_px", SVSLAM_FIELD(odometry.temporal_match.search_radius_px), 1, 2000,
             "px", "around the position predicted from the previous motion"),
      number("min_zncc", SVSLAM_FIELD(odometry.temporal_match.min_zncc), -1, 1, "",
             "acceptance threshold"),
      number("ratio", SVSLAM_FIELD(odometry.temporal_match.ratio), 0.01, 1, "",
             "ratio test on 1 - zncc"),
      number("group_size", SVSLAM_FIELD(odometry.temporal_match.group_size), 0, 32, "",
             "neighbours of the local-group rigidity check; 0 disables"),
      number("group_n_sigma", SVSLAM_FIELD(odometry.temporal_match.group_n_sigma), 0.1, 100, "",
             "tolerance of the group check in standard deviations"),
      number("group_min_fraction", SVSLAM_FIELD(odometry.temporal_match.group_min_fraction), 0, 1,
             "", "share of the group that must agree"),
  };
  return s;
}

ConfigSection motion() {
  ConfigSection s{"motion", "visual motion estimation (src/motion/visual_motion.hpp)", {}};
  s.keys = {
      number("max_point_sigma_m", SVSLAM_FIELD(odometry.motion.max_point_sigma_m), 1e-6, 1e6, "m",
             "points less precise than this are not used"),
      number("gauss_newton_iterations", SVSLAM_FIELD(odometry.motion.gauss_newton_iterations), 1,
             100, "", "per estimate"),
      number("k_start", SVSLAM_FIELD(odometry.motion.k_start), 3, 20, "",
             "outlier loop: reject residuals > k * mean, k from k_start down to 3"),
      number("reject_floor", SVSLAM_FIELD(odometry.motion.reject_floor), 0, 100, "",
             "Mahalanobis residuals below this are never rejected"),
      number("min_inliers", SVSLAM_FIELD(odometry.motion.min_inliers), 3, 10000, "",
             "fewer left: no motion estimated"),
      flag("ransac", SVSLAM_FIELD(odometry.motion.ransac), "seeded RANSAC before the estimation"),
      number("ransac_iterations", SVSLAM_FIELD(odometry.motion.ransac_iterations), 1, 100000, "",
             "RANSAC hypotheses"),
      number("ransac_chi2", SVSLAM_FIELD(odometry.motion.ransac_chi2), 0.1, 1000, "",
             "RANSAC inlier threshold on the squared Mahalanobis residual (chi2 3 dof, 99.9 %)"),
  };
  return s;
}

ConfigSection disparityOffset() {
  ConfigSection s{"disparity_offset",
                  "online estimate of the stereo pair's disparity offset "
                  "(src/motion/disparity_offset.hpp)",
                  {}};
  s.keys = {
      flag("enabled", SVSLAM_FIELD(odometry.disparity_offset.enabled),
           "estimate the offset from the frame-to-frame motion and triangulate with it"),
      number("prior_sigma_px", SVSLAM_FIELD(odometry.disparity_offset.prior_sigma_px), 1e-6, 100,
             "px", "zero-mean prior on the offset"),
      number("max_abs_px", SVSLAM_FIELD(odometry.disparity_offset.max_abs_px), 1e-6, 100, "px",
             "the offset is clamped to +- this"),
      number("gate_sigma", SVSLAM_FIELD(odometry.disparity_offset.gate_sigma), 0.1, 1000, "",
             "a frame's estimate further than this many sigma is not used"),
      number("min_points", SVSLAM_FIELD(odometry.disparity_offset.min_points), 3, 100000, "",
             "motion inliers a frame needs to contribute"),
      number("min_information", SVSLAM_FIELD(odometry.disparity_offset.min_information), 0, 1e12,
             "px^-2", "a frame contributes when it alone fixes the offset to 1/sqrt(this) px"),
  };
  return s;
}

ConfigSection denseStereo() {
  ConfigSection s{"dense_stereo", "dense census stereo (src/stereo/dense_stereo.hpp)", {}};
  s.keys = {
      flag("enabled", SVSLAM_FIELD(odometry.dense),
           "true: dense disparity for the map and as the prior of the stereo match"),
      flag("observation", SVSLAM_FIELD(odometry.dense_observation),
           "with enabled: 3D points by the 8-neighbour combination of seed 001 sec 4.1; false: "
           "triangulation of the matched disparity"),
      choice("method", SVSLAM_FIELD(odometry.dense_stereo.cost), kCostNames,
             "matching cost: census (Hamming) or SAD"),
      number("census_w_px", SVSLAM_FIELD(odometry.dense_stereo.census_w), 3, 15, "px",
             "census window width, odd, census_w_px * census_h_px - 1 <= 64"),
      number("census_h_px", SVSLAM_FIELD(odometry.dense_stereo.census_h), 3, 15, "px",
             "census window height, odd"),
      number("window_w_px", SVSLAM_FIELD(odometry.dense_stereo.window_w), 1, 31, "px",
             "aggregation window width, odd"),
      number("window_h_px", SVSLAM_FIELD(odometry.dense_stereo.window_h), 1, 31, "px",
             "aggregation window height, odd"),
      number("min_disp_px", SVSLAM_FIELD(odometry.dense_stereo.min_disp), 0, 1024, "px",
             "smallest disparity searched"),
      number("max_disp_px", SVSLAM_FIELD(odometry.dense_stereo.max_disp), 1, 1024, "px",
             "one past the largest disparity searched"),
      number("uniqueness_pct", SVSLAM_FIELD(odometry.dense_stereo.uniqueness_pct), 0, 100, "%",
             "best must beat the second best by this much; 0 disables"),
      flag("lr_check", SVSLAM_FIELD(odometry.dense_stereo.lr_check),
           "left-right consistency check"),
      number("lr_max_diff_px", SVSLAM_FIELD(odometry.dense_stereo.lr_max_diff), 0, 64, "px",
             "allowed |d_left - d_right|"),
  };
  return s;
}

ConfigSection clusters() {
  ConfigSection s{
      "clusters", "ROI tracking (seed 004 sec 3.6; src/features/feature_clusters.hpp)", {}};
  s.keys = {
      number("stop_distance_m", SVSLAM_FIELD(odometry.clusters.stop_distance_m), 1e-6, 1e6, "m",
             "complete-link merging stops above this distance"),
      number("min_cluster_size", SVSLAM_FIELD(odometry.clusters.min_cluster_size), 1, 100000, "",
             "smaller clusters are not returned"),
      number("max_points", SVSLAM_FIELD(odometry.clusters.max_points), 1, 4096, "",
             "workspace size; larger inputs are subsampled"),
      number("roi_margin_px", SVSLAM_FIELD(odometry.clusters.roi_margin_px), 0, 1000, "px",
             "added around each cluster's region"),
      choice("roi_radius", SVSLAM_FIELD(odometry.clusters.roi_radius), kRoiRadiusNames,
             "sphere-bound (holds every member) or farthest-point (the seed's rule)"),
      number("min_depth_m", SVSLAM_FIELD(odometry.clusters.min_depth_m), 1e-6, 1e6, "m",
             "clusters whose centre is nearer are dropped"),
      number("unknown_cell_px", SVSLAM_FIELD(odometry.clusters.unknown_cell_px), 4, 1024, "px",
             "grid of the unknown regions"),
  };
  return s;
}

ConfigSection odometry() {
  ConfigSection s{"odometry", "src/odometry/stereo_odometry.hpp", {}};
  s.keys = {
      flag("roi_tracking", SVSLAM_FIELD(odometry.roi_tracking),
           "clustered-feature ROI tracking (see clusters:)"),
      number("unknown_threshold_factor", SVSLAM_FIELD(odometry.unknown_threshold_factor), 0.001, 1,
             "", "detector threshold in unknown regions, relative"),
      number("match_sigma_px", SVSLAM_FIELD(odometry.match_sigma_px), 0.01, 10, "px",
             "matching error between consecutive frames; with dense stereo only 0.5 or 1"),
      number("min_disparity_px", SVSLAM_FIELD(odometry.min_disparity_px), 0.01, 1024, "px",
             "points with a smaller disparity (farther) are not used"),
      number("max_depth_m", SVSLAM_FIELD(odometry.max_depth_m), 0.01, 1e9, "m",
             "points farther than this are not used"),
      number("min_matches", SVSLAM_FIELD(odometry.min_matches), 3, 10000, "",
             "fewer temporal matches: retry with the identity prediction"),
      number("lost_search_radius_px", SVSLAM_FIELD(odometry.lost_search_radius_px), 1, 4000, "px",
             "search radius of the retry and of the first pair (no motion yet)"),
      flag("repredict", SVSLAM_FIELD(odometry.repredict),
           "when the prediction was the identity or poor, the search is predicted again: "
           "rotation by image alignment, then a RANSAC motion of the matches"),
      number("repredict_px", SVSLAM_FIELD(odometry.repredict_px), 0.1, 1000, "px",
             "median distance of the matches from their prediction that makes it poor"),
      flag("ransac_on_repredict", SVSLAM_FIELD(odometry.ransac_on_repredict),
           "the motion of a re-predicted or retried frame by seeded RANSAC"),
  };
  return s;
}

}  // namespace

std::vector<ConfigSection> runConfigSections() {
  return {topLevel(),    detector(), orb(),      stereoMatch(),       temporalMatch(),   motion(), disparityOffset(),
          denseStereo(), clusters(), odometry(), slamConfigSection(), mapConfigSection(),
          loopConfigSection()};
}

const std::vector<RenamedKey>& renamedConfigKeys() {
  static const std::vector<RenamedKey> kRenamed = {
      {"dense_stereo.census_w", "dense_stereo.census_w_px"},
      {"dense_stereo.census_h", "dense_stereo.census_h_px"},
      {"dense_stereo.window_w", "dense_stereo.window_w_px"},
      {"dense_stereo.window_h", "dense_stereo.window_h_px"},
      {"dense_stereo.min_disp", "dense_stereo.min_disp_px"},
      {"dense_stereo.max_disp", "dense_stereo.max_disp_px"},
      {"dense_stereo.lr_max_diff", "dense_stereo.lr_max_diff_px"},
  };
  return kRenamed;
}

}  // namespace svslam::config

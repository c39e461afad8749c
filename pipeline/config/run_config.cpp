#include "pipeline/config/run_config.hpp"

#include "pipeline/config/yaml_config.hpp"

namespace svslam::config {
namespace {

Status readCorners(ConfigReader& r, CornerParams& c) {
  std::string resp = c.response == CornerResponse::kHarris ? "harris" : "shi-tomasi";
  SVSLAM_TRY(r.read("detector.response", resp, {"harris", "shi-tomasi"}));
  c.response = resp == "harris" ? CornerResponse::kHarris : CornerResponse::kShiTomasi;
  SVSLAM_TRY(r.read("detector.sigma_d_px", c.sigma_d_px, 0.5, 5));
  SVSLAM_TRY(r.read("detector.sigma_i_px", c.sigma_i_px, 0.5, 10));
  SVSLAM_TRY(r.read("detector.harris_k", c.harris_k, 0.01, 0.25));
  SVSLAM_TRY(r.read("detector.threshold_rel", c.threshold_rel, 0, 1));
  SVSLAM_TRY(r.read("detector.grid_cols", c.grid_cols, 1, 256));
  SVSLAM_TRY(r.read("detector.grid_rows", c.grid_rows, 1, 256));
  SVSLAM_TRY(r.read("detector.max_per_cell", c.max_per_cell, 1, 10000));
  SVSLAM_TRY(r.read("detector.border_px", c.border_px, 1, 200));
  return Status::ok();
}

Status readOrb(ConfigReader& r, StereoOdometryParams& o) {
  std::string kind = o.detector == PointDetector::kOrb ? "orb" : "corners";
  SVSLAM_TRY(r.read("detector.kind", kind, {"corners", "orb"}));
  o.detector = kind == "orb" ? PointDetector::kOrb : PointDetector::kCorners;
  OrbParams& b = o.orb;
  SVSLAM_TRY(r.read("orb.num_octaves", b.num_octaves, 1, 4));
  SVSLAM_TRY(r.read("orb.fast_threshold", b.fast_threshold, 1, 254));
  SVSLAM_TRY(r.read("orb.orientation_radius_px", b.orientation_radius_px, 3, 15));
  SVSLAM_TRY(r.read("orb.blur_sigma_px", b.blur_sigma_px, 0.5, 4));
  SVSLAM_TRY(r.read("orb.angle_step_deg", b.angle_step_deg, 1, 45));
  SVSLAM_TRY(r.read("orb.pattern_seed", b.pattern_seed));
  SVSLAM_TRY(r.read("orb.grid_cols", b.grid_cols, 1, 256));
  SVSLAM_TRY(r.read("orb.grid_rows", b.grid_rows, 1, 256));
  SVSLAM_TRY(r.read("orb.max_per_cell", b.max_per_cell, 1, 10000));
  return Status::ok();
}

Status readStereoMatch(ConfigReader& r, StereoMatchParams& m) {
  SVSLAM_TRY(r.read("stereo_match.patch_half_px", m.patch_half_px, 1, 15));
  SVSLAM_TRY(r.read("stereo_match.min_disp_px", m.min_disp_px, 0, 1024));
  SVSLAM_TRY(r.read("stereo_match.max_disp_px", m.max_disp_px, 1, 1024));
  SVSLAM_TRY(r.read("stereo_match.min_zncc", m.min_zncc, -1, 1));
  SVSLAM_TRY(r.read("stereo_match.ratio", m.ratio, 0.01, 1));
  SVSLAM_TRY(r.read("stereo_match.ratio_floor", m.ratio_floor, 0, 1));
  SVSLAM_TRY(r.read("stereo_match.prior_radius_px", m.prior_radius_px, 1, 64));
  SVSLAM_TRY(r.read("stereo_match.continuity_check", m.continuity_check));
  SVSLAM_TRY(r.read("stereo_match.continuity_threshold_px", m.continuity_threshold_px, 0.01, 1024));
  SVSLAM_TRY(r.read("stereo_match.recovery", m.recovery));
  SVSLAM_TRY(r.read("stereo_match.recovery_dist_th_px", m.recovery_dist_th_px, 0.01, 100));
  SVSLAM_TRY(r.read("stereo_match.recovery_margin_px", m.recovery_margin_px, 0, 64));
  std::string sigma_mode = m.sigma_mode == StereoSigmaMode::kFixed ? "fixed" : "curvature";
  SVSLAM_TRY(r.read("stereo_match.sigma_mode", sigma_mode, {"curvature", "fixed"}));
  m.sigma_mode = sigma_mode == "fixed" ? StereoSigmaMode::kFixed : StereoSigmaMode::kCurvature;
  SVSLAM_TRY(r.read("stereo_match.sigma_d_px", m.sigma_d_px, 0.01, 10));
  SVSLAM_TRY(r.read("stereo_match.min_sigma_d_px", m.min_sigma_d_px, 0, 10));
  std::string subpixel = m.subpixel == SubpixelMethod::kRefine ? "refine" : "parabola";
  SVSLAM_TRY(r.read("stereo_match.subpixel", subpixel, {"parabola", "refine"}));
  m.subpixel = subpixel == "refine" ? SubpixelMethod::kRefine : SubpixelMethod::kParabola;
  SVSLAM_TRY(r.read("stereo_match.refine_iterations", m.refine.max_iterations, 1, 50));
  if (m.max_disp_px <= m.min_disp_px)
    return Status::invalidArgument(r.name() +
                                   ": key 'stereo_match.max_disp_px' must be > min_disp_px");
  return Status::ok();
}

Status readTemporal(ConfigReader& r, TemporalMatchParams& t) {
  SVSLAM_TRY(r.read("temporal_match.patch_half_px", t.patch_half_px, 1, 15));
  SVSLAM_TRY(r.read("temporal_match.search_radius_px", t.search_radius_px, 1, 2000));
  SVSLAM_TRY(r.read("temporal_match.min_zncc", t.min_zncc, -1, 1));
  SVSLAM_TRY(r.read("temporal_match.ratio", t.ratio, 0.01, 1));
  SVSLAM_TRY(r.read("temporal_match.group_size", t.group_size, 0, 32));
  SVSLAM_TRY(r.read("temporal_match.group_n_sigma", t.group_n_sigma, 0.1, 100));
  SVSLAM_TRY(r.read("temporal_match.group_min_fraction", t.group_min_fraction, 0, 1));
  return Status::ok();
}

Status readMotion(ConfigReader& r, VisualMotionParams& m) {
  SVSLAM_TRY(r.read("motion.max_point_sigma_m", m.max_point_sigma_m, 1e-6, 1e6));
  SVSLAM_TRY(r.read("motion.gauss_newton_iterations", m.gauss_newton_iterations, 1, 100));
  SVSLAM_TRY(r.read("motion.k_start", m.k_start, 3, 20));
  SVSLAM_TRY(r.read("motion.reject_floor", m.reject_floor, 0, 100));
  SVSLAM_TRY(r.read("motion.min_inliers", m.min_inliers, 3, 10000));
  SVSLAM_TRY(r.read("motion.ransac", m.ransac));
  SVSLAM_TRY(r.read("motion.ransac_iterations", m.ransac_iterations, 1, 100000));
  SVSLAM_TRY(r.read("motion.ransac_chi2", m.ransac_chi2, 0.1, 1000));
  return Status::ok();
}

Status readDense(ConfigReader& r, StereoOdometryParams& o) {
  SVSLAM_TRY(r.read("dense_stereo.enabled", o.dense));
  DenseStereoParams& d = o.dense_stereo;
  std::string cost = toString(d.cost);
  SVSLAM_TRY(r.read("dense_stereo.method", cost, {"census", "sad"}));
  parseMatchingCost(cost, d.cost);
  SVSLAM_TRY(r.read("dense_stereo.census_w", d.census_w, 3, 15));
  SVSLAM_TRY(r.read("dense_stereo.census_h", d.census_h, 3, 15));
  SVSLAM_TRY(r.read("dense_stereo.window_w", d.window_w, 1, 31));
  SVSLAM_TRY(r.read("dense_stereo.window_h", d.window_h, 1, 31));
  SVSLAM_TRY(r.read("dense_stereo.min_disp", d.min_disp, 0, 1024));
  SVSLAM_TRY(r.read("dense_stereo.max_disp", d.max_disp, 1, 1024));
  SVSLAM_TRY(r.read("dense_stereo.uniqueness_pct", d.uniqueness_pct, 0, 100));
  SVSLAM_TRY(r.read("dense_stereo.lr_check", d.lr_check));
  SVSLAM_TRY(r.read("dense_stereo.lr_max_diff", d.lr_max_diff, 0, 64));
  if (o.dense) {
    if (Status s = d.validate(); !s)
      return Status::invalidArgument(r.name() + ": dense_stereo: " + s.message());
  }
  return Status::ok();
}

Status readSlam(ConfigReader& r, SlamSystemParams& p) {
  SVSLAM_TRY(r.read("slam.max_landmarks", p.ekf.max_landmarks, 1, 3000));
  SVSLAM_TRY(r.read("slam.max_batch_observations", p.ekf.max_batch_observations, 1, 1000));
  SVSLAM_TRY(r.read("slam.gate_chi2", p.ekf.gate_chi2, 0.1, 1000));
  SVSLAM_TRY(r.read("slam.joseph_form", p.ekf.joseph_form));
  SVSLAM_TRY(r.read("slam.candidate_fraction", p.candidate_fraction, 0.001, 1));
  SVSLAM_TRY(r.read("slam.candidate_min_frames", p.candidate_min_frames, 2, 1000));
  SVSLAM_TRY(r.read("slam.candidate_max_sigma_m", p.candidate_max_sigma_m, 1e-6, 1e6));
  SVSLAM_TRY(r.read("slam.grid_cols", p.grid_cols, 1, 256));
  SVSLAM_TRY(r.read("slam.grid_rows", p.grid_rows, 1, 256));
  SVSLAM_TRY(r.read("slam.max_per_cell", p.max_per_cell, 1, 10000));
  SVSLAM_TRY(r.read("slam.init_sigma_uv_px", p.init_sigma_uv_px, 0.01, 10));
  SVSLAM_TRY(r.read("slam.track_matching_error_px", p.track_matching_error_px, 0.01, 10));
  SVSLAM_TRY(
      r.read("slam.reperception_matching_error_px", p.reperception_matching_error_px, 0.01, 10));
  SVSLAM_TRY(r.read("slam.reperception_tolerance_px", p.reperception_tolerance_px, 0.01, 100));
  SVSLAM_TRY(r.read("slam.reperception_max_radius_px", p.reperception_max_radius_px, 0.01, 1000));
  SVSLAM_TRY(r.read("slam.reperception_min_zncc", p.reperception_min_zncc, -1, 1));
  SVSLAM_TRY(r.read("slam.refine_observations", p.refine_observations));
  SVSLAM_TRY(r.read("slam.patch_half_px", p.patch_half_px, 1, 15));
  SVSLAM_TRY(r.read("slam.max_reperceptions", p.max_reperceptions, 0, 10000));
  SVSLAM_TRY(r.read("slam.max_observations", p.max_observations, 1, 10000));
  SVSLAM_TRY(r.read("slam.track_tolerance_px", p.track_tolerance_px, 0.01, 100));
  SVSLAM_TRY(r.read("slam.landmark_exclusion_px", p.landmark_exclusion_px, 0, 100));
  SVSLAM_TRY(r.read("slam.retire_unseen_frames", p.retire_unseen_frames, 1, 100000));
  SVSLAM_TRY(r.read("slam.lost_rot_sigma_rad", p.lost_rot_sigma_rad, 1e-6, 10));
  SVSLAM_TRY(r.read("slam.lost_trans_sigma_m", p.lost_trans_sigma_m, 1e-6, 1000));
  return Status::ok();
}

}  // namespace

static Status parse(ConfigReader& r, RunConfig& out) {
  SVSLAM_TRY(r.read("source", out.source));
  SVSLAM_TRY(r.read("max_frames", out.max_frames, 0, 100000000));
  SVSLAM_TRY(r.read("threads", out.threads, 1, 256));
  SVSLAM_TRY(r.read("seed", out.seed));
  SVSLAM_TRY(r.read("mode", out.mode, {"ekf", "vo"}));
  SVSLAM_TRY(readSlam(r, out.slam));
  StereoOdometryParams& o = out.odometry;
  SVSLAM_TRY(readCorners(r, o.corners));
  SVSLAM_TRY(readOrb(r, o));
  SVSLAM_TRY(readStereoMatch(r, o.stereo_match));
  SVSLAM_TRY(readTemporal(r, o.temporal_match));
  SVSLAM_TRY(readMotion(r, o.motion));
  SVSLAM_TRY(readDense(r, o));
  SVSLAM_TRY(r.read("odometry.roi_tracking", o.roi_tracking));
  SVSLAM_TRY(r.read("odometry.unknown_threshold_factor", o.unknown_threshold_factor, 0.001, 1));
  SVSLAM_TRY(r.read("clusters.stop_distance_m", o.clusters.stop_distance_m, 1e-6, 1e6));
  SVSLAM_TRY(r.read("clusters.min_cluster_size", o.clusters.min_cluster_size, 1, 100000));
  SVSLAM_TRY(r.read("clusters.max_points", o.clusters.max_points, 1, 4096));
  SVSLAM_TRY(r.read("clusters.roi_margin_px", o.clusters.roi_margin_px, 0, 1000));
  std::string rr =
      o.clusters.roi_radius == RoiRadius::kSphereBound ? "sphere-bound" : "farthest-point";
  SVSLAM_TRY(r.read("clusters.roi_radius", rr, {"sphere-bound", "farthest-point"}));
  o.clusters.roi_radius =
      rr == "sphere-bound" ? RoiRadius::kSphereBound : RoiRadius::kFarthestPoint;
  SVSLAM_TRY(r.read("clusters.min_depth_m", o.clusters.min_depth_m, 1e-6, 1e6));
  SVSLAM_TRY(r.read("clusters.unknown_cell_px", o.clusters.unknown_cell_px, 4, 1024));
  SVSLAM_TRY(r.read("odometry.match_sigma_px", o.match_sigma_px, 0.01, 10));
  SVSLAM_TRY(r.read("odometry.min_disparity_px", o.min_disparity_px, 0.01, 1024));
  SVSLAM_TRY(r.read("odometry.max_depth_m", o.max_depth_m, 0.01, 1e9));
  SVSLAM_TRY(r.read("odometry.min_matches", o.min_matches, 3, 10000));
  SVSLAM_TRY(r.read("odometry.lost_search_radius_px", o.lost_search_radius_px, 1, 4000));
  SVSLAM_TRY(readPipelineConfig(r, out.pipeline, out.lcm, out.service));
  SVSLAM_TRY(r.finish());
  o.motion.seed = out.seed;
  o.dense_stereo.num_stripes = out.threads;
  if (Status s = o.validate(); !s) return Status::invalidArgument(r.name() + ": " + s.message());
  if (Status s = out.slam.validate(); !s)
    return Status::invalidArgument(r.name() + ": " + s.message());
  return Status::ok();
}

Status parseRunConfig(const std::string& yaml_text, const std::string& name, RunConfig& out) {
  auto r = ConfigReader::fromString(yaml_text, name);
  if (!r) return r.status();
  return parse(*r, out);
}

Status loadRunConfig(const std::string& path, RunConfig& out, std::set<std::string>* changed_keys) {
  if (path.empty()) {
    if (changed_keys) changed_keys->clear();  // no file: nothing changes a default
    ConfigReader r;
    return parse(r, out);
  }
  auto r = ConfigReader::fromFile(path);
  if (!r) return r.status();
  const Status s = parse(*r, out);
  if (changed_keys) *changed_keys = r->changedKeys();
  return s;
}

}  // namespace svslam::config

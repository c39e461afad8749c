#include "slam/slam_system.hpp"

#include <algorithm>
#include <cmath>

namespace svslam {

Status SlamSystemParams::validate() const {
  if (Status s = ekf.validate(); !s) return s;
  if (!(candidate_fraction > 0.0 && candidate_fraction <= 1.0))
    return Status::invalidArgument("slam.candidate_fraction must be in (0, 1]");
  if (candidate_min_frames < 2)
    return Status::invalidArgument("slam.candidate_min_frames must be >= 2");
  if (!(candidate_max_sigma_m > 0.0))
    return Status::invalidArgument("slam.candidate_max_sigma_m must be > 0");
  if (grid_cols < 1 || grid_rows < 1 || max_per_cell < 1)
    return Status::invalidArgument("slam.grid_cols, grid_rows and max_per_cell must be >= 1");
  if (!(init_sigma_uv_px > 0.0))
    return Status::invalidArgument("slam.init_sigma_uv_px must be > 0");
  if (!(track_matching_error_px > 0.0) || !(reperception_matching_error_px > 0.0))
    return Status::invalidArgument("slam matching errors must be > 0");
  if (!(track_tolerance_px > 0.0) || !(reperception_tolerance_px > 0.0) ||
      !(reperception_max_radius_px > 0.0))
    return Status::invalidArgument("slam tolerances and radii must be > 0");
  if (max_reperceptions < 0) return Status::invalidArgument("slam.max_reperceptions must be >= 0");
  if (max_observations < 1) return Status::invalidArgument("slam.max_observations must be >= 1");
  if (!(landmark_exclusion_px >= 0.0))
    return Status::invalidArgument("slam.landmark_exclusion_px must be >= 0");
  if (!(reperception_min_zncc >= -1.0f && reperception_min_zncc <= 1.0f))
    return Status::invalidArgument("slam.reperception_min_zncc must be in -1..1");
  if (patch_half_px < 1 || patch_half_px > 15)
    return Status::invalidArgument("slam.patch_half_px must be in 1..15");
  if (retire_unseen_frames < 1)
    return Status::invalidArgument("slam.retire_unseen_frames must be >= 1");
  if (!(lost_rot_sigma_rad > 0.0) || !(lost_trans_sigma_m > 0.0))
    return Status::invalidArgument("slam.lost_rot_sigma_rad and lost_trans_sigma_m must be > 0");
  if (!(map_voxel_m > 0.0) || !std::isfinite(map_voxel_m))
    return Status::invalidArgument("slam.map_voxel_m must be > 0 and finite");
  if (Status s = relocalisation.validate(); !s)
    return Status::invalidArgument("slam.relocalise_* (" + s.message() + ")");
  if (Status s = calibration_uncertainty.validate(); !s)
    return Status::invalidArgument("slam." + s.message());
  // The bearing initialiser's and the monitor's own checks, named by their configuration keys.
  if (!(bearing_init.r_min_m > 0) || !(bearing_init.r_max_m > bearing_init.r_min_m) ||
      !std::isfinite(bearing_init.r_max_m))
    return Status::invalidArgument(
        "slam.bearing_r_min_m must be > 0 and slam.bearing_r_max_m finite and > it");
  if (Status s = bearing_init.validate(); !s)
    return Status::invalidArgument("slam.bearing_* (" + s.message() + ")");
  if (Status s = right_camera.validate(); !s)
    return Status::invalidArgument("slam.right_camera_* (" + s.message() + ")");
  if (!(mono_rot_sigma_rad > 0.0) || !(mono_trans_sigma_m >= 0.0) ||
      !(mono_trans_speed_fraction >= 0.0) ||
      !(mono_trans_sigma_m + mono_trans_speed_fraction > 0.0))
    return Status::invalidArgument(
        "slam.mono_rot_sigma_rad must be > 0, slam.mono_trans_sigma_m and "
        "slam.mono_trans_speed_fraction >= 0 and not both 0");
  if (!(mono_start_rot_sigma_rad > 0.0) || !(mono_start_trans_sigma_m > 0.0))
    return Status::invalidArgument(
        "slam.mono_start_rot_sigma_rad and slam.mono_start_trans_sigma_m must be > 0");
  if (!(mono_track_error_px > 0.0) || !(mono_reperception_error_px > 0.0))
    return Status::invalidArgument(
        "slam.mono_track_error_px and slam.mono_reperception_error_px must be > 0");
  if (mono_max_candidates < 0 || mono_max_candidates > 4096)
    return Status::invalidArgument("slam.mono_max_candidates must be in [0, 4096]");
  if (mono_candidate_min_frames < 2 || mono_candidate_max_frames < mono_candidate_min_frames)
    return Status::invalidArgument(
        "slam.mono_candidate_min_frames must be >= 2 and <= mono_candidate_max_frames");
  if (!(mono_bearing_sigma_px > 0.0) || !(mono_search_px > 0.0))
    return Status::invalidArgument("slam.mono_bearing_sigma_px and mono_search_px must be > 0");
  if (Status s = two_view.validate(); !s)
    return Status::invalidArgument("slam.two_view_* (" + s.message() + ")");
  if (mono_init_points < two_view.min_inliers || mono_init_points > 4096)
    return Status::invalidArgument(
        "slam.mono_init_points must be in [slam.two_view_min_inliers, 4096]");
  if (mono_init_max_frames < 2)
    return Status::invalidArgument("slam.mono_init_max_frames must be >= 2");
  if (!(mono_init_depth_m > 0.0) || !std::isfinite(mono_init_depth_m))
    return Status::invalidArgument("slam.mono_init_depth_m must be > 0 and finite");
  if (!(mono_init_max_rel_sigma > 0.0 && mono_init_max_rel_sigma <= 1.0))
    return Status::invalidArgument("slam.mono_init_max_rel_sigma must be in (0, 1]");
  if (map_reserve < ekf.max_landmarks)
    return Status::invalidArgument("slam.map_reserve must be >= max_landmarks");
  return Status::ok();
}

SlamSystem::SlamSystem(const SlamSystemParams& params, const StereoOdometryParams& odometry,
                       const StereoCalibration& calib, bool left_only)
    : params_(params),
      calib_(calib),
      calib_consider_(calib.exact ? CalibrationConsiderParams{} : params.calibration_uncertainty,
                      calib.f_px),
      drift_consider_(calib.exact ? DriftConsiderParams{} : params.drift_uncertainty),
      vo_(odometry, calib),
      ekf_(params.ekf),
      landmarks_(params.patch_half_px, params.map_reserve, params.map_voxel_m),
      landmark_row_matcher_(odometry.stereo_match),
      right_monitor_(params.right_camera),
      bearing_init_(params.bearing_init),
      two_view_(params.two_view),
      left_only_(left_only) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = vo_.initStatus();
  if (init_status_) init_status_ = ekf_.initStatus();
  if (init_status_) init_status_ = calib_consider_.initStatus();
  if (init_status_) init_status_ = drift_consider_.initStatus();
  if (init_status_) init_status_ = landmark_row_matcher_.initStatus();
  if (init_status_) init_status_ = bearing_init_.initStatus();
  if (init_status_) init_status_ = two_view_.initStatus();
  cell_count_.resize(static_cast<std::size_t>(params.grid_cols * params.grid_rows));
  if (!init_status_) return;
  if (params.relocalisation.enabled && !left_only) {
    reloc_ = std::make_unique<Relocaliser>(params.relocalisation, calib);
    init_status_ = reloc_->initStatus();
    if (!init_status_) return;
  }
  mono_cands_.resize(static_cast<std::size_t>(params.mono_max_candidates));
  mono_patches_.resize(static_cast<std::size_t>(params.mono_max_candidates) *
                       static_cast<std::size_t>((2 * params.patch_half_px + 1) *
                                                (2 * params.patch_half_px + 1)));
  bobs_.reserve(static_cast<std::size_t>(params.max_observations));
  if (left_only && params.mono_scale != MonoScaleSource::kFirstPair) {
    const std::size_t n = static_cast<std::size_t>(params.mono_init_points);
    const int side = 2 * params.patch_half_px + 1;
    init_tracks_.reserve(n);
    init_patches_.resize(n * static_cast<std::size_t>(side * side));
    init_x0_.reserve(n);
    init_x1_.reserve(n);
    init_index_.reserve(n);
  }
  const std::size_t lm = static_cast<std::size_t>(params.ekf.max_landmarks);
  const std::size_t n_obs = static_cast<std::size_t>(params.max_observations);
  preds_.reserve(lm);
  obs_.reserve(n_obs);
  obs_uv_.reserve(n_obs);
  results_.reserve(n_obs);
  prev_landmark_uv_.reserve(lm);
  landmark_uv_.reserve(lm);
  const int side = 2 * params.patch_half_px + 1;
  tmpl_.resize(static_cast<std::size_t>(side * side));
  // First-frame candidates: at most max_per_cell per grid cell.
  const std::size_t n_anchor =
      static_cast<std::size_t>(params.grid_cols * params.grid_rows * params.max_per_cell);
  const std::size_t big_side = static_cast<std::size_t>(4 * params.patch_half_px + 1);
  anchor_points_.reserve(n_anchor);
  anchored_ids_.reserve(n_anchor);
  retired_preds_.reserve(n_anchor);
  anchor_patches_.reserve(n_anchor * big_side * big_side);
  // A search window is at most (2 reperception_max_radius_px + 1)^2 scores.
  const std::size_t r = static_cast<std::size_t>(std::ceil(params.reperception_max_radius_px));
  scores_.reserve((2 * r + 1) * (2 * r + 1));
  // Per stereo point (grown once past this when a frame has more points).
  prev_tracks_.reserve(2048);
  cur_tracks_.reserve(2048);
  exclude_.reserve(2048);
  fresh_.reserve(2048);
}

bool SlamSystem::nearLandmark(const std::vector<Eigen::Vector2f>& landmarks_uv, float u,
                              float v) const {
  const float r2 =
      static_cast<float>(params_.landmark_exclusion_px * params_.landmark_exclusion_px);
  for (const Eigen::Vector2f& l : landmarks_uv) {
    const float du = l.x() - u, dv = l.y() - v;
    if (du * du + dv * dv <= r2) return true;
  }
  return false;
}

void SlamSystem::passTracks() {
  const auto& matches = vo_.matches();
  const auto& prev = vo_.previousPoints();
  cur_tracks_.assign(vo_.points().size(), PointTrack{});
  exclude_.assign(matches.size(), 0);
  for (std::size_t k = 0; k < matches.size(); ++k) {
    PointTrack t = prev_tracks_[static_cast<std::size_t>(matches[k].prev)];
    ++t.track_len;
    cur_tracks_[static_cast<std::size_t>(matches[k].cur)] = t;
    const TrackPoint& p = prev[static_cast<std::size_t>(matches[k].prev)];
    exclude_[k] = (t.candidate || nearLandmark(prev_landmark_uv_, p.u_px, p.v_px)) ? 1 : 0;
  }
}

Status SlamSystem::process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                           const StereoStageOutput& stereo, SlamFrameResult& out,
                           Executor& executor, StageObserver* observer) {
  if (Status s = processFrame(left, right, stereo, out, executor, observer); !s) return s;
  if (out.initializing) return Status::ok();  // no pose yet: the covariance is uninformative
  // The world origin (the first pose, exact) is where the calibration's error and the drift
  // start.
  if (Status s = calib_consider_.process(anchor_pose_, out.T_world_cam, out.pose_cov_consider); !s)
    return s;
  Matrix6d drift_cov;
  if (Status s = drift_consider_.process(anchor_pose_, out.T_world_cam, drift_cov); !s) return s;
  out.pose_cov_consider += drift_cov;
  return Status::ok();
}

Status SlamSystem::processFrame(ImageView<const std::uint8_t> left,
                                ImageView<const std::uint8_t> right,
                           const StereoStageOutput& stereo, SlamFrameResult& out,
                           Executor& executor, StageObserver* observer) {
  if (!init_status_) return init_status_;
  out = SlamFrameResult{};
  if (left_only_ && params_.mono_scale != MonoScaleSource::kFirstPair && !mono_started_) {
    if (Status s = processMonoStart(left, stereo, out); !s) return s;
    if (observer) observer->stageDone("ekf");
    return Status::ok();
  }
  if (left_only_) {
    if (frame_ > 0) {
      if (Status s = processMono(left, stereo, out, executor); !s) return s;
      if (observer) observer->stageDone("ekf");
      return Status::ok();
    }
    // The first pair: the scale source.
    if (Status s = vo_.frontEnd(left, stereo, out.odometry, observer); !s) return s;
    calib_.disparity_offset_px = vo_.calibration().disparity_offset_px;
    if (Status s = startMap(); !s) return s;
    landmark_uv_.clear();
    mapFirstPair(left, out);
    spawnMonoCandidates(left, stereo);
    for (const MonoCandidate& c : mono_cands_) out.mono_candidates += c.alive ? 1 : 0;
    if (observer) observer->stageDone("ekf");
    out.mono = true;
    out.T_world_cam = ekf_.pose();
    out.pose_cov = ekf_.poseCovariance();
    out.landmarks_in_state = ekf_.numLandmarks();
    out.landmarks_in_map = landmarks_.size();
    prev_landmark_uv_.swap(landmark_uv_);
    prev_pose_ = ekf_.pose();
    prev_mono_ = true;
    ++frame_;
    return Status::ok();
  }
  const bool stereo_ok = right_monitor_.process(left, right);
  out.right_camera = static_cast<int>(right_monitor_.state());
  if (!stereo_ok) {
    if (Status s = processMono(left, stereo, out, executor); !s) return s;
    if (observer) observer->stageDone("ekf");
    return Status::ok();
  }
  if (Status s = vo_.frontEnd(left, stereo, out.odometry, observer); !s) return s;
  if (frame_ == 0) {
    prev_tracks_.clear();
    prev_landmark_uv_.clear();
  }
  passTracks();
  out.vme_matches = static_cast<int>(std::count(exclude_.begin(), exclude_.end(), 0));
  if (Status s = vo_.estimateMotion(&exclude_, out.odometry, observer); !s) return s;
  // New landmarks and anchors are triangulated with the odometry's disparity offset.
  calib_.disparity_offset_px = vo_.calibration().disparity_offset_px;
  const OdometryFrameResult& od = out.odometry;

  landmark_uv_.clear();
  if (frame_ == 0) {
    if (Status s = startMap(); !s) return s;
  } else {
    if (prev_mono_) {
      // The odometry's previous frame is the last stereo one: predict as in a mono frame.
      out.stereo_resumed = true;
      if (Status s = predictConstantVelocity(); !s) return s;
    } else {
      const Matrix6d R_u =
          od.tracked ? od.covariance
                     : diagonalMotionCov(params_.lost_rot_sigma_rad, params_.lost_trans_sigma_m);
      if (Status s = ekf_.predict(od.T_cur_prev, R_u); !s) return s;
    }
    if (Status s = observeLandmarks(left, right, out, executor); !s) return s;
    if (Status s = relocaliseIfLost(left, right, stereo, out, executor); !s) return s;
  }
  if (!lost_) selectLandmarks(left, out);  // never from a pose that may be far off
  if (reloc_ && !lost_ && od.tracked && stereo.has_disparity &&
      (frame_ == 0 || out.nis_count >= params_.relocalisation.min_landmarks)) {
    bool kept = false;
    if (Status s = reloc_->offer(left, stereo.disparity, ekf_.pose(), ekf_.poseCovariance(),
                                 frame_, kept);
        !s)
      return s;
  }
  if (observer) observer->stageDone("ekf");

  out.T_world_cam = ekf_.pose();
  out.pose_cov = ekf_.poseCovariance();
  out.landmarks_in_state = ekf_.numLandmarks();
  out.landmarks_in_map = landmarks_.size();
  prev_tracks_.swap(cur_tracks_);
  prev_landmark_uv_.swap(landmark_uv_);
  // The constant-velocity motion of a following mono frame: a relocalised pose jumped, so the
  // frame's own measured motion (none: the identity).
  last_motion_ = !out.relocalised ? ekf_.pose().inverse() * prev_pose_
                 : od.tracked     ? od.T_cur_prev
                                  : Eigen::Isometry3d::Identity();
  prev_pose_ = ekf_.pose();
  prev_mono_ = false;
  for (MonoCandidate& c : mono_cands_) c.alive = false;
  ++frame_;
  return Status::ok();
}

Status SlamSystem::relocaliseIfLost(ImageView<const std::uint8_t> left,
                                    ImageView<const std::uint8_t> right,
                                    const StereoStageOutput& stereo, SlamFrameResult& out,
                                    Executor& executor) {
  if (!reloc_) return Status::ok();
  const RelocaliserParams& rp = params_.relocalisation;
  const bool few = out.nis_count < rp.min_landmarks;
  if (!few) {
    lost_ = false;  // the landmarks confirm the pose
  } else if (!out.odometry.tracked) {
    lost_ = true;
  }
  if (!lost_) {
    lost_frames_ = 0;
    return Status::ok();
  }
  out.lost = true;
  if (!stereo.has_disparity) return Status::ok();
  RelocalisationResult rr;
  if (Status s = reloc_->relocalise(left, stereo.disparity, ekf_.pose(), frame_, rr); !s)
    return s;
  if (!rr.found) {
    out.relocalisation_failed = true;
    // Frames that could have been relocalised (keyframes verified against) and were not: a
    // black or blank frame does not count.
    if (rr.candidates_tried > 0 && ++lost_frames_ >= rp.max_lost_frames) {
      lost_ = false;  // given up: on from the prediction (new landmarks and keyframes again)
      lost_frames_ = 0;
    }
    return Status::ok();
  }
  if (Status s = ekf_.replacePose(rr.T_world_cam, rr.covariance); !s) return s;
  lost_ = false;
  lost_frames_ = 0;
  out.relocalised = true;
  out.relocalisation_inliers = rr.inliers;
  return observeLandmarks(left, right, out, executor);  // from the pose found
}

Status SlamSystem::observeLandmarks(ImageView<const std::uint8_t> left,
                                    ImageView<const std::uint8_t> right, SlamFrameResult& out,
                                    Executor& executor) {
  restoreAnchors(left, out);
  searchLandmarks(left, right, out);
  if (obs_.empty()) return Status::ok();
  if (Status s = ekf_.update(obs_, results_, &executor); !s) return s;
  applyObservations(out, false);
  return Status::ok();
}

Status SlamSystem::startMap() {
  if (Status s = ekf_.reset(Eigen::Isometry3d::Identity(), Matrix6d::Zero()); !s) return s;
  anchor_pose_ = ekf_.pose();
  anchor_points_.clear();
  anchor_patches_.clear();
  anchored_ids_.clear();
  return Status::ok();
}

Matrix6d SlamSystem::diagonalMotionCov(double rot_sigma_rad, double trans_sigma_m) {
  Matrix6d R_u = Matrix6d::Zero();
  R_u.diagonal().head<3>().setConstant(rot_sigma_rad * rot_sigma_rad);
  R_u.diagonal().tail<3>().setConstant(trans_sigma_m * trans_sigma_m);
  return R_u;
}

void SlamSystem::applyObservations(SlamFrameResult& out, bool bearings) {
  const std::size_t n = bearings ? bobs_.size() : obs_.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!results_[i].accepted) {
      ++out.gated;
      continue;
    }
    if (bearings) {
      out.bearing_nis_sum += results_[i].mahalanobis_d2;
      ++out.bearing_count;
    } else {
      out.nis_sum += results_[i].mahalanobis_d2;
      ++out.nis_count;
    }
    landmarks_.observed(results_[i].id, frame_);
    landmark_uv_.push_back(obs_uv_[i]);
  }
}

Status SlamSystem::applyLoopCorrection(const Eigen::Isometry3d& C_new_old,
                                       const Matrix6d& cov_world, Eigen::Isometry3d& moved) {
  if (!C_new_old.matrix().allFinite())
    return Status::invalidArgument("loop correction: C_new_old is not finite");
  const Eigen::Isometry3d before = ekf_.pose();
  if (Status s = ekf_.updatePosition((C_new_old * before).translation(),
                                     cov_world.bottomRightCorner<3, 3>());
      !s)
    return Status(s.code(), "loop correction: " + s.message());
  moved = ekf_.pose() * before.inverse();
  for (int id : ekf_.landmarkIds()) landmarks_.rotateView(id, moved.linear());
  return Status::ok();
}

std::vector<MapLandmark> SlamSystem::map() const {
  std::vector<MapLandmark> out = landmarks_.landmarks();
  for (MapLandmark& m : out)
    if (m.active) (void)ekf_.landmark(m.id, m.p_world, m.cov);
  return out;
}

}  // namespace svslam

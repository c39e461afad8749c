// SlamSystem, camera loss (slam_system.hpp, "Camera loss"): a frame processed from the left
// image alone. The landmarks of the state are observed by their bearing; new ones are
// initialised from two bearings of a tracked left corner (seed 003, BearingInitializer).
#include <algorithm>
#include <cmath>

#include "slam/patch_tracking.hpp"
#include "slam/slam_system.hpp"
#include "stereo/reprojection.hpp"

namespace svslam {

Status SlamSystem::predictConstantVelocity() {
  // Monocular mode's second frame: no velocity measured yet (the first frame's is zero).
  if (left_only_ && frame_ == 1)
    return ekf_.predict(last_motion_, diagonalMotionCov(params_.mono_start_rot_sigma_rad,
                                                        params_.mono_start_trans_sigma_m));
  const double trans_sigma_m = params_.mono_trans_sigma_m +
                               params_.mono_trans_speed_fraction * last_motion_.translation().norm();
  return ekf_.predict(last_motion_, diagonalMotionCov(params_.mono_rot_sigma_rad, trans_sigma_m));
}

Status SlamSystem::processMono(ImageView<const std::uint8_t> left, const StereoStageOutput& stereo,
                               SlamFrameResult& out, Executor& executor) {
  out.mono = true;
  landmark_uv_.clear();
  preds_.clear();
  if (frame_ == 0) {
    // No stereo pair yet: the world frame is the first camera; nothing fixes the scale.
    if (Status s = startMap(); !s) return s;
  } else {
    if (Status s = predictConstantVelocity(); !s) return s;
    restoreAnchors(left, out, &stereo.corner_px);
    // Monocular mode, active search: the tracked landmarks (best predicted first), an update,
    // then the re-perceptions, predicted from the updated filter. Camera loss: one pass (on
    // the synthetic camera-loss flights two passes ended 1.8-10x further off at seeds 1-3).
    const ImageView<const std::uint8_t> none;
    const bool two_pass = left_only_;
    if (two_pass) searchLandmarks(left, none, out, SearchPass::kFirst);
    int observed = 0;
    if (two_pass && !bobs_.empty()) {
      if (Status s = ekf_.updateBearings(bobs_, results_, &executor); !s) return s;
      const int gated_before = out.gated;
      applyObservations(out, true);
      observed = static_cast<int>(bobs_.size()) - (out.gated - gated_before);
    }
    searchLandmarks(left, none, out, two_pass ? SearchPass::kRest : SearchPass::kAll, observed);
    if (!bobs_.empty()) {
      if (Status s = ekf_.updateBearings(bobs_, results_, &executor); !s) return s;
      applyObservations(out, true);
    }
  }
  trackMonoCandidates(left, out);
  spawnMonoCandidates(left, stereo);
  for (const MonoCandidate& c : mono_cands_) out.mono_candidates += c.alive ? 1 : 0;

  out.T_world_cam = ekf_.pose();
  out.pose_cov = ekf_.poseCovariance();
  out.landmarks_in_state = ekf_.numLandmarks();
  out.landmarks_in_map = landmarks_.size();
  prev_landmark_uv_.swap(landmark_uv_);
  last_motion_ = ekf_.pose().inverse() * prev_pose_;
  prev_pose_ = ekf_.pose();
  prev_mono_ = true;
  ++frame_;
  return Status::ok();
}

void SlamSystem::mapFirstPair(ImageView<const std::uint8_t> left, SlamFrameResult& out) {
  const auto& pts = vo_.points();
  const int h = params_.patch_half_px;
  // The most precise stereo points first (ties: ascending index).
  std::vector<int>& order = fresh_;
  order.clear();
  std::vector<double>& sigma = depth_scratch_;
  sigma.assign(pts.size(), 0.0);
  for (std::size_t j = 0; j < pts.size(); ++j) {
    sigma[j] = std::sqrt(pts[j].cov.trace());
    const int x = static_cast<int>(std::lround(pts[j].u_px));
    const int y = static_cast<int>(std::lround(pts[j].v_px));
    if (std::isfinite(sigma[j]) && sigma[j] <= params_.candidate_max_sigma_m &&
        patchInside(left, x, y, h + 1))
      order.push_back(static_cast<int>(j));
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const double sa = sigma[static_cast<std::size_t>(a)], sb = sigma[static_cast<std::size_t>(b)];
    return sa != sb ? sa < sb : a < b;
  });
  std::fill(cell_count_.begin(), cell_count_.end(), 0);
  const float min_d2 = static_cast<float>(4 * h * h);
  for (const int j : order) {
    const TrackPoint& p = pts[static_cast<std::size_t>(j)];
    const std::size_t cell = gridCell(p.u_px, p.v_px);
    if (cell_count_[cell] >= params_.max_per_cell) continue;
    const float x = std::round(p.u_px), y = std::round(p.v_px);
    bool crowded = false;  // two landmarks closer than 2 h px would share their patch
    for (const Eigen::Vector2f& l : landmark_uv_)
      crowded = crowded || (l - Eigen::Vector2f(x, y)).squaredNorm() < min_d2;
    if (crowded) continue;
    if (ekf_.numLandmarks() >= params_.ekf.max_landmarks) break;
    const StereoPoint sp =
        reprojectPixel(calib_, x, y, p.d_px, p.sigma_d_px, params_.init_sigma_uv_px);
    auto id = ekf_.addLandmarkFromExactPose(anchor_pose_, sp.p_cam, sp.cov);
    if (!id) continue;
    landmarks_.add(*id, frame_, left, static_cast<int>(x), static_cast<int>(y), anchor_pose_,
                   sp.p_cam);
    landmarks_.info(*id).anchored = true;
    anchored_ids_.push_back(*id);
    landmark_uv_.emplace_back(x, y);
    ++cell_count_[cell];
    ++out.added;
  }
}

void SlamSystem::trackMonoCandidates(ImageView<const std::uint8_t> left, SlamFrameResult& out) {
  const int h = params_.patch_half_px, side = 2 * h + 1;
  const double f = calib_.f_px, cx = calib_.cx_px, cy = calib_.cy_px;
  const Eigen::Isometry3d T = ekf_.pose();
  const Eigen::Matrix3d Rt = T.linear().transpose();
  const double sigma = params_.mono_bearing_sigma_px / f;
  // Depth guess for the prediction: the median depth of the landmarks predicted in the image
  // (the scene's scale), else the middle of the vision range.
  double depth = 0.5 * (params_.bearing_init.r_min_m + params_.bearing_init.r_max_m);
  if (!preds_.empty()) {
    std::vector<double>& zs = depth_scratch_;
    zs.clear();
    for (const SearchPrediction& p : preds_) zs.push_back(p.z_cam.z());
    std::nth_element(zs.begin(), zs.begin() + static_cast<std::ptrdiff_t>(zs.size() / 2), zs.end());
    depth = zs[zs.size() / 2];
  }
  const auto bearingWorld = [&](double u, double v) {
    return (T.linear() * Eigen::Vector3d((u - cx) / f, (v - cy) / f, 1.0)).normalized();
  };
  const int r = static_cast<int>(std::ceil(params_.mono_search_px));
  for (std::size_t k = 0; k < mono_cands_.size(); ++k) {
    MonoCandidate& c = mono_cands_[k];
    if (!c.alive) continue;
    c.alive = false;  // until found again
    std::uint8_t* tmpl = mono_patches_.data() + k * static_cast<std::size_t>(side * side);
    const Eigen::Vector3d p = Rt * (c.o_last_w + depth * c.d_last_w - T.translation());
    if (!(p.z() > 0.1)) continue;
    const int pu = static_cast<int>(std::lround(f * p.x() / p.z() + cx));
    const int pv = static_cast<int>(std::lround(f * p.y() / p.z() + cy));
    double u = 0, v = 0;
    if (!findPatch(left, tmpl, h, pu, pv, r, params_.reperception_min_zncc, u, v)) continue;
    c.alive = true;
    ++c.frames;
    c.u = static_cast<float>(u);
    c.v = static_cast<float>(v);
    c.o_last_w = T.translation();
    c.d_last_w = bearingWorld(u, v);
    samplePatch(left, u, v, h, tmpl);  // the template follows the corner, centred on it
    if (c.frames < params_.mono_candidate_min_frames) continue;
    // Two views: the first and this one, from the rounded pixel (the centre of the patch the
    // landmark keeps; the rounding, <= 0.5 px, is inside mono_bearing_sigma_px).
    const int xi = static_cast<int>(std::lround(u)), yi = static_cast<int>(std::lround(v));
    bearing_views_.assign({{c.o0_w, c.d0_w, sigma}, {T.translation(), bearingWorld(xi, yi), sigma}});
    const std::vector<BearingView<3>>& views = bearing_views_;
    BearingEstimate<3> est;
    const Status s = bearing_init_.process(views, c.serial, est);
    if (!s || est.outcome != BearingEstimate<3>::Outcome::kInitialised) {
      if (c.frames >= params_.mono_candidate_max_frames) c.alive = false;
      continue;
    }
    c.alive = false;
    if (!makeRoom(out)) continue;
    const Eigen::Vector3d z_cam = Rt * (est.mean_m - T.translation());
    Eigen::Matrix3d R_z = Rt * est.cov_m2 * Rt.transpose();
    R_z = 0.5 * (R_z + R_z.transpose()).eval();
    auto id = ekf_.addLandmark(z_cam, R_z);
    if (!id) continue;
    landmarks_.add(*id, frame_, left, xi, yi, T, z_cam);
    landmark_uv_.emplace_back(static_cast<float>(xi), static_cast<float>(yi));
    ++out.bearing_added;
    ++out.added;
  }
}

void SlamSystem::strongestCornersFirst(const StereoStageOutput& stereo, std::vector<int>& order) {
  order.clear();
  for (std::size_t j = 0; j < stereo.corner_px.size(); ++j) order.push_back(static_cast<int>(j));
  const bool have_resp = stereo.corner_resp.size() == stereo.corner_px.size();
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const float ra = have_resp ? stereo.corner_resp[static_cast<std::size_t>(a)] : 0.0f,
                rb = have_resp ? stereo.corner_resp[static_cast<std::size_t>(b)] : 0.0f;
    return ra != rb ? ra > rb : a < b;
  });
}

void SlamSystem::spawnMonoCandidates(ImageView<const std::uint8_t> left,
                                     const StereoStageOutput& stereo) {
  const int h = params_.patch_half_px, side = 2 * h + 1;
  const double f = calib_.f_px, cx = calib_.cx_px, cy = calib_.cy_px;
  const auto cellOf = [&](float u, float v) { return gridCell(u, v); };
  std::fill(cell_count_.begin(), cell_count_.end(), 0);
  for (const Eigen::Vector2f& l : prev_landmark_uv_) ++cell_count_[cellOf(l.x(), l.y())];
  for (const Eigen::Vector2f& l : landmark_uv_) ++cell_count_[cellOf(l.x(), l.y())];
  std::size_t free_slots = 0;
  for (const MonoCandidate& c : mono_cands_) {
    if (c.alive)
      ++cell_count_[cellOf(c.u, c.v)];
    else
      ++free_slots;
  }
  if (free_slots == 0) return;
  // Strongest corners first (ties: ascending index).
  std::vector<int>& order = fresh_;
  strongestCornersFirst(stereo, order);
  const Eigen::Isometry3d T = ekf_.pose();
  const float min_d2 = static_cast<float>(4 * h * h);
  std::size_t slot = 0;
  for (const int j : order) {
    if (free_slots == 0) break;
    const Eigen::Vector2f& px = stereo.corner_px[static_cast<std::size_t>(j)];
    if (!insideWithMargin(left, px.x(), px.y(), h + 2)) continue;
    const std::size_t cell = cellOf(px.x(), px.y());
    if (cell_count_[cell] >= params_.max_per_cell) continue;
    bool crowded = false;  // within 2 h px of a landmark seen now or of a candidate
    for (const Eigen::Vector2f& l : landmark_uv_)
      crowded = crowded || (l - px).squaredNorm() < min_d2;
    for (const MonoCandidate& c : mono_cands_)
      crowded = crowded || (c.alive && (Eigen::Vector2f(c.u, c.v) - px).squaredNorm() < min_d2);
    if (crowded) continue;
    while (mono_cands_[slot].alive) ++slot;
    MonoCandidate& c = mono_cands_[slot];
    c = MonoCandidate{};
    c.alive = true;
    c.first_frame = frame_;
    c.frames = 1;
    c.serial = mono_serial_++;
    c.u = px.x();
    c.v = px.y();
    c.o0_w = c.o_last_w = T.translation();
    c.d0_w = c.d_last_w =
        (T.linear() * Eigen::Vector3d((px.x() - cx) / f, (px.y() - cy) / f, 1.0)).normalized();
    samplePatch(left, px.x(), px.y(), h,
                mono_patches_.data() + slot * static_cast<std::size_t>(side * side));
    ++cell_count_[cell];
    --free_slots;
  }
}

}  // namespace svslam

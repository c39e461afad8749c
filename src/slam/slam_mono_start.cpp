// SlamSystem, monocular mode without a stereo pair (slam_system.hpp, "Monocular mode";
// slam.mono_scale none or altitude): the two-view start. The reference frame is the world
// origin; its corners are tracked frame to frame until TwoViewInitializer accepts the relative
// pose of the reference and the current frame; the map is then made of the triangulated points,
// in the unit where their median depth is mono_init_depth_m (none) or where the current camera's
// height above their plane is the altimeter's reading (altitude).
#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "slam/patch_tracking.hpp"
#include "slam/slam_system.hpp"

namespace svslam {

namespace {

// T^a for a rigid motion: the rotation angle and the translation scaled by a (the mean motion
// of one frame among 1 / a, constant velocity).
Eigen::Isometry3d fractionOf(const Eigen::Isometry3d& T, double a) {
  const Eigen::AngleAxisd aa(T.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(a * aa.angle(), aa.axis()).toRotationMatrix();
  out.translation() = a * T.translation();
  return out;
}

// A two-view start needs at least this many landmarks (a pose needs three bearings; the rest is
// margin against the first frames' losses).
constexpr int kMinStartLandmarks = 8;

}  // namespace

void SlamSystem::startReference(ImageView<const std::uint8_t> left,
                                const StereoStageOutput& stereo) {
  reference_frame_ = frame_;
  init_tracks_.clear();
  const int h = params_.patch_half_px, side = 2 * h + 1;
  const int cells = params_.grid_cols * params_.grid_rows;
  const int per_cell = (params_.mono_init_points + cells - 1) / cells;
  std::fill(cell_count_.begin(), cell_count_.end(), 0);
  // Strongest corners first (ties: ascending index), spread over the grid, 2 h px apart.
  std::vector<int>& order = fresh_;
  strongestCornersFirst(stereo, order);
  const float min_d2 = static_cast<float>(4 * h * h);
  for (const int j : order) {
    if (static_cast<int>(init_tracks_.size()) >= params_.mono_init_points) break;
    const Eigen::Vector2f& px = stereo.corner_px[static_cast<std::size_t>(j)];
    if (!insideWithMargin(left, px.x(), px.y(), h + 2)) continue;
    const std::size_t cell = gridCell(px.x(), px.y());
    if (cell_count_[cell] >= per_cell) continue;
    bool crowded = false;
    for (const InitTrack& t : init_tracks_)
      crowded = crowded || (Eigen::Vector2f(t.u0, t.v0) - px).squaredNorm() < min_d2;
    if (crowded) continue;
    InitTrack t;
    t.alive = true;
    t.u0 = t.u = px.x();
    t.v0 = t.v = px.y();
    samplePatch(left, px.x(), px.y(), h,
                init_patches_.data() + init_tracks_.size() * static_cast<std::size_t>(side * side));
    init_tracks_.push_back(t);
    ++cell_count_[cell];
  }
}

void SlamSystem::trackReference(ImageView<const std::uint8_t> left) {
  const int h = params_.patch_half_px, side = 2 * h + 1;
  const int r = static_cast<int>(std::ceil(params_.mono_search_px));
  std::vector<Eigen::Vector2d>& flow = init_x1_;  // scratch here; refilled by the caller
  flow.clear();
  for (std::size_t k = 0; k < init_tracks_.size(); ++k) {
    InitTrack& t = init_tracks_[k];
    if (!t.alive) continue;
    std::uint8_t* tmpl = init_patches_.data() + k * static_cast<std::size_t>(side * side);
    const int pu = static_cast<int>(std::lround(t.u + init_flow_.x()));
    const int pv = static_cast<int>(std::lround(t.v + init_flow_.y()));
    double u = 0, v = 0;
    if (!findPatch(left, tmpl, h, pu, pv, r, params_.reperception_min_zncc, u, v)) {
      t.alive = false;
      continue;
    }
    flow.emplace_back(u - t.u, v - t.v);
    t.u = static_cast<float>(u);
    t.v = static_cast<float>(v);
    samplePatch(left, u, v, h, tmpl);  // the template follows the corner
  }
  // The median flow predicts the next frame's search (the camera's motion continues).
  init_flow_.setZero();
  if (flow.empty()) return;
  std::vector<double>& m = depth_scratch_;
  for (int axis = 0; axis < 2; ++axis) {
    m.clear();
    for (const Eigen::Vector2d& d : flow) m.push_back(d[axis]);
    std::nth_element(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(m.size() / 2), m.end());
    init_flow_[axis] = static_cast<float>(m[m.size() / 2]);
  }
}

Status SlamSystem::processMonoStart(ImageView<const std::uint8_t> left,
                                    const StereoStageOutput& stereo, SlamFrameResult& out) {
  out.mono = true;
  landmark_uv_.clear();
  bool restart = frame_ == 0;
  if (!restart) {
    trackReference(left);
    const double f = calib_.f_px, cx = calib_.cx_px, cy = calib_.cy_px;
    init_x0_.clear();
    init_x1_.clear();
    init_index_.clear();
    for (std::size_t k = 0; k < init_tracks_.size(); ++k) {
      const InitTrack& t = init_tracks_[k];
      if (!t.alive) continue;
      init_x0_.emplace_back((t.u0 - cx) / f, (t.v0 - cy) / f);
      init_x1_.emplace_back((t.u - cx) / f, (t.v - cy) / f);
      init_index_.push_back(static_cast<int>(k));
    }
    out.mono_candidates = static_cast<int>(init_index_.size());
    const bool wait_altitude =
        params_.mono_scale == MonoScaleSource::kAltitude && !(altitude_m_ > 0.0);
    if (static_cast<int>(init_index_.size()) < params_.two_view.min_inliers) {
      restart = true;
    } else if (wait_altitude) {
      restart = frame_ - reference_frame_ >= params_.mono_init_max_frames;
    } else {
      if (Status s = two_view_.process(init_x0_, init_x1_, f, static_cast<std::uint64_t>(frame_),
                                       two_view_result_);
          !s)
        return s;
      if (two_view_result_.initialised) {
        if (Status s = mapTwoView(left, out); !s) return s;
      }
      restart = !mono_started_ && frame_ - reference_frame_ >= params_.mono_init_max_frames;
    }
  }
  if (restart) {
    if (Status s = startMap(); !s) return s;
    startReference(left, stereo);
  }
  if (!mono_started_) {
    // No map yet: the world origin, with a covariance that says nothing is known.
    out.initializing = true;
    out.T_world_cam = Eigen::Isometry3d::Identity();
    out.pose_cov = diagonalMotionCov(1.0, params_.mono_init_depth_m);
    prev_pose_ = Eigen::Isometry3d::Identity();
    prev_mono_ = true;
    ++frame_;
    return Status::ok();
  }
  spawnMonoCandidates(left, stereo);
  out.mono_candidates = 0;
  for (const MonoCandidate& c : mono_cands_) out.mono_candidates += c.alive ? 1 : 0;
  out.T_world_cam = ekf_.pose();
  out.pose_cov = ekf_.poseCovariance();
  out.landmarks_in_state = ekf_.numLandmarks();
  out.landmarks_in_map = landmarks_.size();
  prev_landmark_uv_.swap(landmark_uv_);
  // The constant-velocity prediction of the next frame: the mean motion since the reference.
  last_motion_ = fractionOf(ekf_.pose().inverse(), 1.0 / (frame_ - reference_frame_));
  prev_pose_ = ekf_.pose();
  prev_mono_ = true;
  ++frame_;
  return Status::ok();
}

Status SlamSystem::mapTwoView(ImageView<const std::uint8_t> left, SlamFrameResult& out) {
  const TwoViewResult& tv = two_view_result_;
  const int h = params_.patch_half_px;
  const double f = calib_.f_px;
  // The unit. mono_scale none: the median depth of the kept points (reference camera) is
  // mono_init_depth_m. altitude: the current camera's distance to the plane fitted to the kept
  // points (least squares: through their centroid, normal along the smallest eigenvector of
  // their scatter) is the altimeter's reading.
  std::vector<double>& z = depth_scratch_;
  z.clear();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < init_index_.size(); ++i)
    if (tv.inlier[i]) {
      z.push_back(tv.p0[i].z());
      centroid += tv.p0[i];
    }
  if (z.size() < 3) return Status::ok();
  double scale = 0;
  if (params_.mono_scale == MonoScaleSource::kAltitude) {
    centroid /= static_cast<double>(z.size());
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < init_index_.size(); ++i)
      if (tv.inlier[i]) scatter += (tv.p0[i] - centroid) * (tv.p0[i] - centroid).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
    const Eigen::Vector3d normal = eig.eigenvectors().col(0);
    const Eigen::Vector3d o_cur = -tv.R_1_0.transpose() * tv.t_1_0;  // unit baseline
    const double height = std::abs(normal.dot(o_cur - centroid));
    scale = altitude_m_ / height;
  } else {
    std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
    scale = params_.mono_init_depth_m / z[z.size() / 2];
  }
  if (!(scale > 0.0) || !std::isfinite(scale)) return Status::ok();
  Eigen::Isometry3d T_cur_ref = Eigen::Isometry3d::Identity();
  T_cur_ref.linear() = tv.R_1_0;
  T_cur_ref.translation() = scale * tv.t_1_0;
  const Eigen::Isometry3d T_world_cur = T_cur_ref.inverse();  // world = reference camera
  const Eigen::Vector3d o1 = T_world_cur.translation();
  const double sigma = params_.mono_bearing_sigma_px / f;

  // Each kept point with its linearised two-view covariance (poses taken as exact):
  // C = (sum_k (I - d_k d_k^T) / (sigma r_k)^2)^-1 over the two bearings d_k at range r_k.
  struct Pick {
    int i;
    double sigma_m;
    Eigen::Vector3d p_world;
    Eigen::Matrix3d cov;
  };
  std::vector<Pick> picks;
  picks.reserve(init_index_.size());
  for (std::size_t i = 0; i < init_index_.size(); ++i) {
    if (!tv.inlier[i]) continue;
    const Eigen::Vector3d P = scale * tv.p0[i];
    const Eigen::Vector3d d0 = P.normalized();
    const Eigen::Vector3d d1 = (P - o1).normalized();
    const double r0 = P.norm(), r1 = (P - o1).norm();
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d A = (I - d0 * d0.transpose()) / (sigma * sigma * r0 * r0) +
                              (I - d1 * d1.transpose()) / (sigma * sigma * r1 * r1);
    Eigen::Matrix3d C;
    bool invertible = false;
    A.computeInverseWithCheck(C, invertible);
    if (!invertible || !C.allFinite()) continue;
    C = 0.5 * (C + C.transpose()).eval();
    const double s = std::sqrt(C.trace());
    if (!(s <= params_.mono_init_max_rel_sigma * P.z())) continue;
    picks.push_back({static_cast<int>(i), s, P, C});
  }
  std::sort(picks.begin(), picks.end(), [](const Pick& a, const Pick& b) {
    return a.sigma_m != b.sigma_m ? a.sigma_m < b.sigma_m : a.i < b.i;
  });
  // Spread over the grid of the current image, 2 h px apart, at most max_landmarks.
  std::fill(cell_count_.begin(), cell_count_.end(), 0);
  const float min_d2 = static_cast<float>(4 * h * h);
  std::vector<Pick> chosen;
  chosen.reserve(picks.size());
  landmark_uv_.clear();
  for (const Pick& p : picks) {
    if (static_cast<int>(chosen.size()) >= params_.ekf.max_landmarks) break;
    const InitTrack& t = init_tracks_[static_cast<std::size_t>(init_index_[static_cast<std::size_t>(p.i)])];
    const float x = std::round(t.u), y = std::round(t.v);
    if (!patchInside(left, static_cast<int>(x), static_cast<int>(y), h + 1)) continue;
    const std::size_t cell = gridCell(x, y);
    if (cell_count_[cell] >= params_.max_per_cell) continue;
    bool crowded = false;
    for (const Eigen::Vector2f& l : landmark_uv_)
      crowded = crowded || (l - Eigen::Vector2f(x, y)).squaredNorm() < min_d2;
    if (crowded) continue;
    chosen.push_back(p);
    landmark_uv_.emplace_back(x, y);
    ++cell_count_[cell];
  }
  if (static_cast<int>(chosen.size()) < kMinStartLandmarks) {
    landmark_uv_.clear();
    return Status::ok();  // not enough: the tracks go on
  }
  // The filter at the current frame; its pose uncertain as the monocular second frame's (the
  // first bearing updates set it). The landmarks are the reference's (exact origin).
  if (Status s = ekf_.reset(T_world_cur, diagonalMotionCov(params_.mono_start_rot_sigma_rad,
                                                           params_.mono_start_trans_sigma_m));
      !s)
    return s;
  anchor_pose_ = Eigen::Isometry3d::Identity();
  for (std::size_t k = 0; k < chosen.size(); ++k) {
    const Pick& p = chosen[k];
    auto id = ekf_.addLandmarkFromExactPose(anchor_pose_, p.p_world, p.cov);
    if (!id) continue;
    const Eigen::Vector2f& uv = landmark_uv_[k];
    landmarks_.add(*id, frame_, left, static_cast<int>(uv.x()), static_cast<int>(uv.y()),
                   T_world_cur, T_world_cur.inverse() * p.p_world);
    landmarks_.info(*id).anchored = true;
    anchored_ids_.push_back(*id);
    ++out.added;
  }
  mono_started_ = true;
  out.altitude_scaled = params_.mono_scale == MonoScaleSource::kAltitude;
  return Status::ok();
}

}  // namespace svslam

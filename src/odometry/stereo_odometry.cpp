#include "odometry/stereo_odometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "stereo/reprojection.hpp"

namespace svslam {


StereoOdometry::StereoOdometry(const StereoOdometryParams& params, const StereoCalibration& calib)
    : params_(params),
      calib_(calib),
      stage_(params, calib),
      temporal_matcher_(params.temporal_match),
      motion_(params.motion) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = calib.validate();
  if (init_status_) init_status_ = stage_.initStatus();
  if (init_status_ && params.roi_tracking) {
    clusterer_ = std::make_unique<FeatureClusters>(params.clusters);
    init_status_ = clusterer_->initStatus();
  }
  if (init_status_) {
    prev_left_.resize(calib.width, calib.height);
    cur_left_.resize(calib.width, calib.height);
    own_.corner_px.reserve(2048);
    own_.stereo.reserve(2048);
    prev_.reserve(2048);
    cur_.reserve(2048);
    matches_.reserve(2048);
    pairs_.reserve(2048);
    motion_result_.inlier.reserve(2048);
  }
}

StereoOdometry::~StereoOdometry() = default;

void StereoOdometry::resetTracking() {
  has_prev_ = false;
  completed_ = false;
  have_rois_ = false;
  prev_clusters_.clear();
  cur_clusters_.clear();
  last_motion_ = Eigen::Isometry3d::Identity();
  motion_known_ = false;
}

void StereoOdometry::buildPoints() {
  cur_.clear();
  const double min_d = std::max(params_.min_disparity_px,
                                calib_.f_px * calib_.baseline_m / params_.max_depth_m);
  for (const StereoMatch& m : in_->stereo) {
    if (!(m.d_px >= min_d)) continue;
    StereoPoint sp;
    if (disp_) {
      if (!neighbourhoodPoint(disp_->disparity_px.cview(), disp_->sigma_d_px.cview(),
                              calib_, m.u_px, m.v_px, params_.match_sigma_px, 5, sp))
        continue;
    } else {
      sp = reprojectPixel(calib_, m.u_px, m.v_px, m.d_px, m.sigma_d_px, params_.match_sigma_px);
    }
    if (!sp.p_cam.allFinite() || !sp.cov.allFinite()) continue;
    TrackPoint tp;
    tp.u_px = m.u_px;
    tp.v_px = m.v_px;
    tp.p_cam = sp.p_cam;
    tp.cov = sp.cov;
    tp.d_px = m.d_px;
    tp.sigma_d_px = m.sigma_d_px;
    cur_.push_back(tp);
  }
}

void StereoOdometry::applyRois(OdometryFrameResult& out) {
  if (!clusterer_->project(prev_clusters_, last_motion_, calib_, roi_)) return;
  if (roi_.rois.empty()) return;
  have_rois_ = true;
  out.rois = static_cast<int>(roi_.rois.size());
  const float thr_roi = static_cast<float>(params_.corners.threshold_rel) *
                        (params_.detector == PointDetector::kOrb ? 0.0f : own_.max_response);
  std::vector<Eigen::Vector2f>& corner_px_ = own_.corner_px;
  std::vector<float>& corner_resp_ = own_.corner_resp;
  // Keep: corners inside a left ROI that reach the normal threshold (disparity bounded by the
  // union of the right ROIs of the ROIs holding it), and corners of unknown cells (full range).
  std::size_t w = 0;
  ranges_.clear();
  for (std::size_t i = 0; i < corner_px_.size(); ++i) {
    const Eigen::Vector2f p = corner_px_[i];
    int d0 = 1 << 30, d1 = -(1 << 30);
    bool in_roi = false;
    for (const ClusterRoi& r : roi_.rois) {
      if (!r.left.contains(p.x(), p.y())) continue;
      in_roi = true;
      if (r.right.empty()) continue;
      // Right patch centre x - d inside [right.x0, right.x1).
      d0 = std::min(d0, static_cast<int>(std::floor(p.x())) - r.right.x1 + 1);
      d1 = std::max(d1, static_cast<int>(std::ceil(p.x())) - r.right.x0);
    }
    const bool unknown = roi_.isUnknown(p.x(), p.y());
    if (in_roi && corner_resp_[i] >= thr_roi) {
      // A point of an unknown cell can also sit in a ROI corner region: full range then.
      ranges_.emplace_back(unknown ? 0 : d0 - 1, unknown ? (1 << 30) : d1 + 1);
    } else if (unknown) {
      ranges_.emplace_back(0, 1 << 30);
      ++out.unknown_corners;
    } else {
      ++out.roi_dropped;
      continue;
    }
    corner_px_[w] = p;
    corner_resp_[w] = corner_resp_[i];
    ++w;
  }
  corner_px_.resize(w);
  corner_resp_.resize(w);
  // Temporal matching: each previous point is searched inside its cluster's left ROI.
  regions_.assign(prev_.size(), Eigen::Vector4i(0, 0, 0, 0));  // no restriction
  for (const ClusterRoi& r : roi_.rois) {
    if (r.whole_image) continue;
    for (const int m : prev_clusters_[static_cast<std::size_t>(r.cluster)].members)
      regions_[static_cast<std::size_t>(m)] = Eigen::Vector4i(r.left.x0, r.left.y0, r.left.x1, r.left.y1);
  }
}

bool StereoOdometry::observe(const TrackPoint& p, double matching_error_px,
                             StereoPoint& out) const {
  if (disp_)
    return neighbourhoodPoint(disp_->disparity_px.cview(), disp_->sigma_d_px.cview(),
                              calib_, p.u_px, p.v_px, matching_error_px, 5, out);
  if (!(p.d_px > 0.0f)) return false;
  out = reprojectPixel(calib_, p.u_px, p.v_px, p.d_px, p.sigma_d_px, matching_error_px);
  return out.p_cam.allFinite() && out.cov.allFinite();
}

Status StereoOdometry::process(ImageView<const std::uint8_t> left,
                               ImageView<const std::uint8_t> right, OdometryFrameResult& out,
                               Executor& executor, StageObserver* observer) {
  if (Status s = frontEnd(left, right, out, executor, observer); !s) return s;
  return estimateMotion(nullptr, out, observer);
}

Status StereoOdometry::frontEnd(ImageView<const std::uint8_t> left,
                                ImageView<const std::uint8_t> right, OdometryFrameResult& out,
                                Executor& executor, StageObserver* observer) {
  if (!init_status_) return init_status_;
  if (Status s = stage_.process(left, right, own_, executor, observer); !s) return s;
  return frontEnd(left, right, own_, out, executor, observer);
}

Status StereoOdometry::frontEnd(ImageView<const std::uint8_t> left,
                                ImageView<const std::uint8_t> right,
                                const StereoStageOutput& stereo, OdometryFrameResult& out,
                                Executor& executor, StageObserver* observer) {
  if (!init_status_) return init_status_;
  if (left.width != calib_.width || left.height != calib_.height || right.width != calib_.width ||
      right.height != calib_.height)
    return Status::invalidArgument("odometry: image size differs from the calibration's");
  if (stereo.has_disparity != params_.dense)
    return Status::invalidArgument("odometry: the stereo stage output does not match the params");
  auto done = [&](const char* stage) {
    if (observer) observer->stageDone(stage);
  };
  out = OdometryFrameResult{};
  out.frame = frame_;
  in_frame_ = false;
  if (completed_) {  // the last frame becomes the previous one
    prev_.swap(cur_);
    std::swap(prev_left_, cur_left_);
    prev_clusters_.swap(cur_clusters_);
    has_prev_ = true;
    completed_ = false;
  }
  in_ = &stereo;
  disp_ = stereo.has_disparity ? &stereo.disparity : nullptr;
  have_rois_ = false;
  const bool roi_mode = !stereo.matched;
  if (roi_mode) {  // detection and matching depend on the previous frame's clusters
    if (Status s = stage_.detect(left, own_, executor); !s) return s;
    if (clusterer_ && has_prev_ && !prev_clusters_.empty()) applyRois(out);
    done("detect");
    ImageView<const float> prior;
    if (disp_) prior = disp_->disparity_px.cview();
    if (Status s = stage_.match(left, right, prior, have_rois_ ? &ranges_ : nullptr, own_); !s)
      return s;
    own_.matched = true;
    in_ = &own_;
  }
  out.corners = static_cast<int>(in_->corner_px.size());
  out.stereo_stats = in_->stereo_stats;
  buildPoints();
  out.stereo_points = static_cast<int>(cur_.size());
  for (int y = 0; y < left.height; ++y)
    std::memcpy(cur_left_.row(y), left.row(y), static_cast<std::size_t>(left.width));
  if (roi_mode) done("stereo_match");

  matches_.clear();
  if (has_prev_) {
    const PinholeCamera cam = calib_.leftCamera();
    // Without a measured motion yet (the first pair, or after a reset) the identity prediction
    // is searched as widely as a retry after a loss.
    const float radius = motion_known_ ? 0.0f : params_.lost_search_radius_px;
    Status s = temporal_matcher_.process(prev_left_.cview(), prev_, left, cur_, last_motion_, cam,
                                         matches_, out.temporal_stats, radius,
                                         have_rois_ ? &regions_ : nullptr);
    if (!s) return s;
    if (static_cast<int>(matches_.size()) < params_.min_matches) {
      out.retried = true;
      s = temporal_matcher_.process(prev_left_.cview(), prev_, left, cur_,
                                    Eigen::Isometry3d::Identity(), cam, matches_,
                                    out.temporal_stats, params_.lost_search_radius_px);
      if (!s) return s;
    }
    out.temporal_matches = static_cast<int>(matches_.size());
  }
  if (clusterer_) {  // clusters of this frame's points, for the next frame's ROIs
    cluster_pts_.clear();
    cluster_quality_.clear();
    for (const TrackPoint& p : cur_) {
      cluster_pts_.push_back(p.p_cam);
      cluster_quality_.push_back(static_cast<float>(std::sqrt(p.cov.trace())));
    }
    if (Status s = clusterer_->process(cluster_pts_, cluster_quality_, cur_clusters_); !s) return s;
  }
  done("temporal_match");
  in_frame_ = true;
  return Status::ok();
}

Status StereoOdometry::estimateMotion(const std::vector<std::uint8_t>* exclude,
                                      OdometryFrameResult& out, StageObserver* observer) {
  if (!in_frame_) return Status::failedPrecondition("odometry: estimateMotion without frontEnd");
  if (exclude && exclude->size() != matches_.size())
    return Status::invalidArgument("odometry: exclusion mask size differs from the matches");
  in_frame_ = false;
  ++frame_;
  Eigen::Isometry3d T_cur_prev = last_motion_;
  if (has_prev_) {
    pairs_.clear();
    for (std::size_t k = 0; k < matches_.size(); ++k) {
      if (exclude && (*exclude)[k]) continue;
      const TemporalMatch& m = matches_[k];
      const TrackPoint& p = prev_[static_cast<std::size_t>(m.prev)];
      const TrackPoint& c = cur_[static_cast<std::size_t>(m.cur)];
      pairs_.push_back({p.p_cam, p.cov, c.p_cam, c.cov});
    }
    VisualMotionResult& vm = motion_result_;
    // Failure reasons are written into out.failure's own buffer (no temporary string).
    if (static_cast<int>(pairs_.size()) < params_.min_matches) {
      out.failure.assign("too few temporal matches (")
          .append(std::to_string(pairs_.size()))
          .append(")");
    } else if (Status ms = motion_.process(pairs_, vm); !ms) {
      out.failure.assign("motion estimation: ").append(ms.message());
    } else if (!vm.T_cur_prev.matrix().allFinite() || !vm.covariance.allFinite()) {
      out.failure.assign("motion estimation: non-finite result");
    } else {
      out.tracked = true;
      motion_known_ = true;
      T_cur_prev = vm.T_cur_prev;
      out.covariance = vm.covariance;
      out.inliers = vm.used;
    }
    last_motion_ = T_cur_prev;
    T_first_cam_ = T_first_cam_ * T_cur_prev.inverse();
    out.T_cur_prev = T_cur_prev;
  } else {
    out.T_cur_prev = Eigen::Isometry3d::Identity();
    out.tracked = out.frame == 0;
    if (out.frame != 0) out.failure = "tracking reset";
  }
  if (observer) observer->stageDone("motion");
  out.T_first_cam = T_first_cam_;
  completed_ = true;  // becomes the previous frame at the next frontEnd()
  return Status::ok();
}

}  // namespace svslam

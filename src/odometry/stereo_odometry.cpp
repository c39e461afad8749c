#include "odometry/stereo_odometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

namespace svslam {

StereoOdometry::StereoOdometry(const StereoOdometryParams& params, const StereoCalibration& calib)
    : params_(params),
      calib_(calib),
      temporal_matcher_(params.temporal_match),
      motion_(params.motion) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = calib.validate();
  if (init_status_) {
    prev_left_.resize(calib.width, calib.height);
    cur_left_.resize(calib.width, calib.height);
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
  last_motion_ = Eigen::Isometry3d::Identity();
  motion_known_ = false;
}

TrackingFeedback StereoOdometry::feedback() const {
  TrackingFeedback f;
  f.has_previous = completed_ || has_prev_;
  f.T_cur_prev = last_motion_;
  return f;
}

bool StereoOdometry::observe(const TrackPoint& p, double matching_error_px,
                             StereoPoint& out) const {
  return stereoObservation(calib_, disp_, p.u_px, p.v_px, p.d_px, p.sigma_d_px, matching_error_px,
                           out);
}

Status StereoOdometry::process(ImageView<const std::uint8_t> left, const StereoStageOutput& stereo,
                               OdometryFrameResult& out, StageObserver* observer) {
  if (Status s = frontEnd(left, stereo, out, observer); !s) return s;
  return estimateMotion(nullptr, out, observer);
}

Status StereoOdometry::frontEnd(ImageView<const std::uint8_t> left, const StereoStageOutput& stereo,
                                OdometryFrameResult& out, StageObserver* observer) {
  if (!init_status_) return init_status_;
  if (left.width != calib_.width || left.height != calib_.height)
    return Status::invalidArgument("odometry: image size differs from the calibration's");
  if (stereo.has_disparity != params_.dense || !stereo.finished)
    return Status::invalidArgument("odometry: the stereo stage output does not match the params");
  out = OdometryFrameResult{};
  out.frame = frame_;
  in_frame_ = false;
  if (completed_) {  // the last frame becomes the previous one
    prev_.swap(cur_);
    std::swap(prev_left_, cur_left_);
    has_prev_ = true;
    completed_ = false;
  }
  if (stereo.has_rois && stereo.prev_regions.size() != prev_.size())
    return Status::invalidArgument("odometry: the stereo stage's ROIs are of another frame");
  disp_ = stereo.has_disparity && params_.dense_observation ? &stereo.disparity : nullptr;
  out.corners = static_cast<int>(stereo.corner_px.size());
  out.stereo_stats = stereo.stereo_stats;
  out.rois = stereo.rois;
  out.roi_dropped = stereo.roi_dropped;
  out.unknown_corners = stereo.unknown_corners;
  cur_.assign(stereo.points.begin(), stereo.points.end());  // keeps its capacity
  out.stereo_points = static_cast<int>(cur_.size());
  for (int y = 0; y < left.height; ++y)
    std::memcpy(cur_left_.row(y), left.row(y), static_cast<std::size_t>(left.width));

  matches_.clear();
  if (has_prev_) {
    const PinholeCamera cam = calib_.leftCamera();
    // Without a measured motion yet (the first pair, or after a reset) the identity prediction
    // is searched as widely as a retry after a loss.
    const float radius = motion_known_ ? 0.0f : params_.lost_search_radius_px;
    Status s = temporal_matcher_.process(prev_left_.cview(), prev_, left, cur_, last_motion_, cam,
                                         matches_, out.temporal_stats, radius,
                                         stereo.has_rois ? &stereo.prev_regions : nullptr);
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
  if (observer) observer->stageDone("temporal_match");
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
      out.motion_rms_mahalanobis = vm.rms_mahalanobis;
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

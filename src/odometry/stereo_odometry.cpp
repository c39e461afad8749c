#include "odometry/stereo_odometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

namespace svslam {
namespace {

// The motion of the guided re-matching: seeded RANSAC (the first pass may hold many wrong
// matches), otherwise the estimator's settings.
VisualMotionParams bootstrapParams(VisualMotionParams p) {
  p.ransac = true;
  return p;
}

// The alignment's levels, the coarsest kept at 8x8 pixels or more for small images.
RotationAlignmentParams alignmentParams(RotationAlignmentParams p, int width, int height) {
  while (p.coarsest_level > 1 && ((width >> p.coarsest_level) < 8 || (height >> p.coarsest_level) < 8))
    --p.coarsest_level;
  p.finest_level = std::min(p.finest_level, p.coarsest_level);
  return p;
}

}  // namespace

StereoOdometry::StereoOdometry(const StereoOdometryParams& params, const StereoCalibration& calib)
    : params_(params),
      calib_(calib),
      temporal_matcher_(params.temporal_match),
      motion_(params.motion),
      bootstrap_motion_(bootstrapParams(params.motion)),
      disparity_offset_(params.disparity_offset, calib.f_px * calib.baseline_m),
      rotation_alignment_(alignmentParams(params.rotation_alignment, calib.width, calib.height),
                          std::max(calib.width, 16), std::max(calib.height, 16)) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = calib.validate();
  if (init_status_) init_status_ = disparity_offset_.initStatus();
  if (init_status_) {
    prev_left_.resize(calib.width, calib.height);
    cur_left_.resize(calib.width, calib.height);
    prev_.reserve(2048);
    cur_.reserve(2048);
    matches_.reserve(2048);
    rematches_.reserve(2048);
    errors_.reserve(2048);
    bootstrap_result_.inlier.reserve(2048);
    starts_.reserve(2);
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
  if ((stereo.has_disparity != params_.dense && !stereo.left_only) || !stereo.finished)
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
    if (params_.repredict &&
        (!motion_known_ || static_cast<int>(matches_.size()) < params_.min_matches ||
         medianPredictionError(last_motion_, cam) > params_.repredict_px)) {
      if (Status rs = repredict(left, cam, out); !rs) return rs;
    }
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

double StereoOdometry::medianPredictionError(const Eigen::Isometry3d& T_cur_prev,
                                             const PinholeCamera& cam) {
  errors_.clear();
  for (const TemporalMatch& m : matches_) {
    const Eigen::Vector3d X = T_cur_prev * prev_[static_cast<std::size_t>(m.prev)].p_cam;
    double u = 0.0, v = 0.0;
    if (!cam.project(X.x(), X.y(), X.z(), u, v)) continue;
    const TrackPoint& c = cur_[static_cast<std::size_t>(m.cur)];
    errors_.push_back(std::hypot(u - c.u_px, v - c.v_px));
  }
  if (errors_.empty()) return 0.0;
  const auto mid = errors_.begin() + static_cast<std::ptrdiff_t>(errors_.size() / 2);
  std::nth_element(errors_.begin(), mid, errors_.end());
  return *mid;
}

void StereoOdometry::fillPairs(const std::vector<TemporalMatch>& matches,
                               const std::vector<std::uint8_t>* exclude) {
  pairs_.clear();
  for (std::size_t k = 0; k < matches.size(); ++k) {
    if (exclude && (*exclude)[k]) continue;
    const TrackPoint& p = prev_[static_cast<std::size_t>(matches[k].prev)];
    const TrackPoint& c = cur_[static_cast<std::size_t>(matches[k].cur)];
    // Both points moved to the current disparity offset (the stage triangulated them without).
    const double fb = calib_.f_px * calib_.baseline_m, delta = calib_.disparity_offset_px;
    const double sp = disparityOffsetScale(p.p_cam.z(), fb, delta);
    const double sc = disparityOffsetScale(c.p_cam.z(), fb, delta);
    pairs_.push_back({sp * p.p_cam, sp * sp * p.cov, sc * c.p_cam, sc * sc * c.cov});
  }
}

int StereoOdometry::bootstrap(const std::vector<TemporalMatch>& matches) {
  fillPairs(matches, nullptr);
  if (static_cast<int>(pairs_.size()) < params_.motion.min_inliers) return 0;
  if (!bootstrap_motion_.process(pairs_, bootstrap_result_)) return 0;
  if (!bootstrap_result_.T_cur_prev.matrix().allFinite()) return 0;
  return bootstrap_result_.used;
}

Status StereoOdometry::repredict(ImageView<const std::uint8_t> left, const PinholeCamera& cam,
                                 OdometryFrameResult& out) {
  // (a) Rotation-aware prediction: the turn by image alignment from the constant-velocity
  // rotation and from none, with the constant-velocity translation, searched as widely as a
  // retry (a close scene's parallax is not in the rotation). The ROI regions were placed with
  // the poor prediction, so they are not used by the second passes.
  // Without a measured motion the first pass already searched widely around the identity.
  // (An image under 16x16 pixels has no alignment: process() then fails and (b) alone runs.)
  RotationAlignmentResult rot;
  if (motion_known_) starts_.assign({last_motion_.linear(), Eigen::Matrix3d::Identity()});
  if (motion_known_ && rotation_alignment_.process(prev_left_.cview(), left, cam, starts_, rot)) {
    Eigen::Isometry3d T_pred = last_motion_;
    T_pred.linear() = rot.R_cur_prev;
    Status s = temporal_matcher_.process(prev_left_.cview(), prev_, left, cur_, T_pred, cam,
                                         rematches_, rematch_stats_,
                                         params_.lost_search_radius_px, nullptr);
    if (!s) return s;
    if (rematches_.size() > matches_.size()) {
      matches_.swap(rematches_);
      out.temporal_stats = rematch_stats_;
      out.repredicted = true;
    }
  }
  // (b) Guided re-matching around the seeded RANSAC motion of the matches, kept when the
  // RANSAC motion of the new matches has at least as many inliers.
  const int inliers = bootstrap(matches_);
  if (inliers == 0) return Status::ok();
  const Eigen::Isometry3d T_boot = bootstrap_result_.T_cur_prev;
  Status s = temporal_matcher_.process(prev_left_.cview(), prev_, left, cur_, T_boot, cam,
                                       rematches_, rematch_stats_, 0.0f, nullptr);
  if (!s) return s;
  if (static_cast<int>(rematches_.size()) > inliers && bootstrap(rematches_) >= inliers) {
    matches_.swap(rematches_);
    out.temporal_stats = rematch_stats_;
    out.repredicted = true;
  }
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
    fillPairs(matches_, exclude);
    VisualMotionResult& vm = motion_result_;
    // Failure reasons are written into out.failure's own buffer (no temporary string).
    if (static_cast<int>(pairs_.size()) < params_.min_matches) {
      out.failure.assign("too few temporal matches (")
          .append(std::to_string(pairs_.size()))
          .append(")");
    } else if (Status ms = (params_.ransac_on_repredict && (out.repredicted || out.retried)
                                ? bootstrap_motion_
                                : motion_)
                               .process(pairs_, vm);
               !ms) {
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
      if (Status ds = disparity_offset_.process(pairs_, vm.inlier, vm.T_cur_prev,
                                                out.disparity_offset_frame);
          !ds)
        return ds;
      calib_.disparity_offset_px = disparity_offset_.offsetPx();
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
  out.disparity_offset_px = calib_.disparity_offset_px;
  completed_ = true;  // becomes the previous frame at the next frontEnd()
  return Status::ok();
}

}  // namespace svslam

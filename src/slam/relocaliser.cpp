#include "slam/relocaliser.hpp"

#include <algorithm>

#include "loop/relative_pose.hpp"

namespace svslam {

Status RelocaliserParams::validate() const {
  if (Status s = keyframe.validate(); !s) return Status(s.code(), "relocalisation: " + s.message());
  if (Status s = verify.validate(); !s) return Status(s.code(), "relocalisation: " + s.message());
  if (max_keyframes < 1 || max_keyframes > 100000)
    return Status::invalidArgument("relocalisation: max_keyframes must be in 1..100000");
  if (max_candidates < 1 || max_candidates > 1000)
    return Status::invalidArgument("relocalisation: max_candidates must be in 1..1000");
  if (min_landmarks < 0 || min_landmarks > 10000)
    return Status::invalidArgument("relocalisation: min_landmarks must be in 0..10000");
  if (max_lost_frames < 1 || max_lost_frames > 100000)
    return Status::invalidArgument("relocalisation: max_lost_frames must be in 1..100000");
  return Status::ok();
}

Relocaliser::Relocaliser(const RelocaliserParams& params, const StereoCalibration& calib)
    : params_(params),
      selector_(params.keyframe),
      builder_(params.keyframe, calib),
      verifier_(params.verify) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = builder_.initStatus();
  if (init_status_) init_status_ = verifier_.initStatus();
  if (init_status_) {
    ring_.reserve(static_cast<std::size_t>(params.max_keyframes));
    order_.reserve(static_cast<std::size_t>(params.max_keyframes));
  }
}

Status Relocaliser::offer(ImageView<const std::uint8_t> left, const DisparityResult& dense,
                          const Eigen::Isometry3d& T_world_cam,
                          const Eigen::Matrix<double, 6, 6>& pose_cov, std::int64_t frame,
                          bool& kept) {
  kept = false;
  if (!init_status_) return init_status_;
  if (!T_world_cam.matrix().allFinite() || !pose_cov.allFinite())
    return Status::invalidArgument("relocalisation: non-finite pose or covariance");
  if (!selector_.isKeyframe(T_world_cam)) return Status::ok();
  query_.id = static_cast<int>(frame);
  query_.frame = frame;
  query_.T_world_cam = T_world_cam;
  query_.pose_cov = pose_cov;
  const Status s = builder_.process(left, dense, query_);
  if (!s) return s.code() == StatusCode::kFailedPrecondition ? Status::ok() : s;  // few points
  const double median_depth_m = query_.median_depth_m;
  if (ring_.size() < static_cast<std::size_t>(params_.max_keyframes)) {
    ring_.push_back(query_);
  } else {  // the oldest keyframe's slot (a swap: no allocation once full)
    std::swap(ring_[next_], query_);
    next_ = (next_ + 1) % ring_.size();
  }
  selector_.accept(T_world_cam, median_depth_m);
  kept = true;
  return Status::ok();
}

Status Relocaliser::relocalise(ImageView<const std::uint8_t> left, const DisparityResult& dense,
                               const Eigen::Isometry3d& T_world_pred, std::int64_t frame,
                               RelocalisationResult& out) {
  out = RelocalisationResult{};
  if (!init_status_) return init_status_;
  if (!T_world_pred.matrix().allFinite())
    return Status::invalidArgument("relocalisation: non-finite predicted pose");
  if (ring_.empty()) {
    out.reason = "no keyframe kept yet";
    return Status::ok();
  }
  query_.id = -1;
  query_.frame = frame;
  const Status s = builder_.process(left, dense, query_);
  if (!s) {
    if (s.code() != StatusCode::kFailedPrecondition) return s;
    out.reason = "too few points in the frame";
    return Status::ok();
  }
  order_.clear();
  for (std::size_t k = 0; k < ring_.size(); ++k)
    order_.emplace_back(
        (ring_[k].T_world_cam.translation() - T_world_pred.translation()).squaredNorm(), k);
  const std::size_t n = std::min(order_.size(), static_cast<std::size_t>(params_.max_candidates));
  std::partial_sort(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(n), order_.end());
  out.reason = "no keyframe verified";
  for (std::size_t i = 0; i < n; ++i) {
    const Keyframe& kf = ring_[order_[i].second];
    LoopConstraint lc;
    if (Status vs = verifier_.process(query_, kf, lc); !vs) return vs;
    ++out.candidates_tried;
    if (!lc.accepted) continue;
    // T_world_cur = T_world_kf T_qk^-1: factors (T_world_kf, T_kq) with T_kq's covariance
    // from the constraint's through the inversion Jacobian.
    const Eigen::Isometry3d T_kq = lc.T_query_candidate.inverse();
    const Matrix6d J = inverseJacobian(lc.T_query_candidate);
    std::vector<Matrix6d> A;
    const Eigen::Isometry3d T = productJacobians({kf.T_world_cam, T_kq}, A);
    Matrix6d C = A[0] * kf.pose_cov * A[0].transpose() +
                 A[1] * (J * lc.covariance * J.transpose()) * A[1].transpose();
    C = 0.5 * (C + C.transpose()).eval();
    if (!T.matrix().allFinite() || !isValidCovariance(C)) continue;
    out.found = true;
    out.T_world_cam = T;
    out.covariance = C;
    out.keyframe_frame = kf.frame;
    out.inliers = lc.inliers;
    out.reason = "";
    return Status::ok();
  }
  return Status::ok();
}

}  // namespace svslam

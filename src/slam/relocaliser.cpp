#include "slam/relocaliser.hpp"

#include <algorithm>
#include <cmath>

#include "loop/relative_pose.hpp"

namespace svslam {

Status RelocaliserParams::validate() const {
  if (Status s = keyframe.validate(); !s) return Status(s.code(), "relocalisation: " + s.message());
  if (Status s = verify.validate(); !s) return Status(s.code(), "relocalisation: " + s.message());
  if (max_keyframes < 1 || max_keyframes > 100000)
    return Status::invalidArgument("relocalisation: max_keyframes must be in 1..100000");
  if (pending_keyframes < 0 || pending_keyframes > 100)
    return Status::invalidArgument("relocalisation: pending_keyframes must be in 0..100");
  if (max_builds_per_frame < 1 || max_builds_per_frame > 100)
    return Status::invalidArgument("relocalisation: max_builds_per_frame must be in 1..100");
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
      verifier_(params.verify),
      calib_(calib) {
  init_status_ = params.validate();
  if (init_status_) init_status_ = builder_.initStatus();
  if (init_status_) init_status_ = verifier_.initStatus();
  if (init_status_) {
    ring_.reserve(static_cast<std::size_t>(params.max_keyframes));
    order_.reserve(static_cast<std::size_t>(params.max_keyframes + params.pending_keyframes));
    // Preallocated (and so touched) here: first touches of fresh pages in the loop cost tens of
    // milliseconds per slot at 1024x768 on the VM.
    pending_.resize(static_cast<std::size_t>(params.pending_keyframes));
    for (Pending& p : pending_) {
      p.left.resize(calib.width, calib.height);
      p.dense.disparity_px.resize(calib.width, calib.height);
      p.dense.sigma_d_px.resize(calib.width, calib.height);
    }
    built_now_.reserve(static_cast<std::size_t>(params.max_builds_per_frame));
  }
}

int Relocaliser::pendingKeyframes() const {
  int n = 0;
  for (const Pending& p : pending_) n += p.used ? 1 : 0;
  return n;
}

bool Relocaliser::medianDepth(const DisparityResult& dense, double& depth_m) {
  disparities_.clear();
  const ImageF32& d = dense.disparity_px;
  for (int y = 0; y < d.height(); y += 4)
    for (int x = 0; x < d.width(); x += 4) {
      const float v = d(x, y) + static_cast<float>(calib_.disparity_offset_px);
      if (std::isfinite(v) && v > 0.0f) disparities_.push_back(v);
    }
  if (disparities_.size() < 16) return false;
  auto mid = disparities_.begin() + static_cast<std::ptrdiff_t>(disparities_.size() / 2);
  std::nth_element(disparities_.begin(), mid, disparities_.end());
  depth_m = calib_.depthFromDisparity(*mid);  // the median depth: depth falls with disparity
  return std::isfinite(depth_m) && depth_m > 0.0;
}

void Relocaliser::addToRing(Keyframe& kf) {
  if (ring_.size() < static_cast<std::size_t>(params_.max_keyframes)) {
    ring_.push_back(kf);
  } else {  // the oldest keyframe's slot (a swap: no allocation once full)
    std::swap(ring_[next_], kf);
    next_ = (next_ + 1) % ring_.size();
  }
}

Status Relocaliser::keepPending(ImageView<const std::uint8_t> left, const DisparityResult& dense,
                                const Eigen::Isometry3d& T_world_cam,
                                const Eigen::Matrix<double, 6, 6>& pose_cov, std::int64_t frame,
                                bool& kept) {
  if (left.width != calib_.width || left.height != calib_.height ||
      dense.disparity_px.width() != calib_.width || dense.disparity_px.height() != calib_.height ||
      dense.sigma_d_px.width() != calib_.width || dense.sigma_d_px.height() != calib_.height)
    return Status::invalidArgument("relocalisation: image or disparity not of calibration size");
  double median_depth_m = 0;
  if (!medianDepth(dense, median_depth_m)) return Status::ok();  // too few points: not kept
  Pending& p = pending_[pending_next_];
  pending_next_ = (pending_next_ + 1) % pending_.size();
  p.left.resize(left.width, left.height);
  p.dense.disparity_px.resize(left.width, left.height);
  p.dense.sigma_d_px.resize(left.width, left.height);
  for (int y = 0; y < left.height; ++y) {
    std::copy_n(left.row(y), left.width, p.left.row(y));
    std::copy_n(dense.disparity_px.row(y), left.width, p.dense.disparity_px.row(y));
    std::copy_n(dense.sigma_d_px.row(y), left.width, p.dense.sigma_d_px.row(y));
  }
  p.T_world_cam = T_world_cam;
  p.pose_cov = pose_cov;
  p.frame = frame;
  p.used = true;
  selector_.accept(T_world_cam, median_depth_m);
  kept = true;
  return Status::ok();
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
  if (!pending_.empty()) return keepPending(left, dense, T_world_cam, pose_cov, frame, kept);
  query_.id = static_cast<int>(frame);
  query_.frame = frame;
  query_.T_world_cam = T_world_cam;
  query_.pose_cov = pose_cov;
  const Status s = builder_.process(left, dense, query_);
  if (!s) return s.code() == StatusCode::kFailedPrecondition ? Status::ok() : s;  // few points
  const double median_depth_m = query_.median_depth_m;
  addToRing(query_);
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
  if (ring_.empty() && pendingKeyframes() == 0) {
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
  const Eigen::Vector3d t_pred = T_world_pred.translation();
  for (std::size_t k = 0; k < ring_.size(); ++k)
    order_.push_back({(ring_[k].T_world_cam.translation() - t_pred).squaredNorm(), k, false});
  for (std::size_t k = 0; k < pending_.size(); ++k)
    if (pending_[k].used)
      order_.push_back({(pending_[k].T_world_cam.translation() - t_pred).squaredNorm(), k, true});
  const std::size_t n = std::min(order_.size(), static_cast<std::size_t>(params_.max_candidates));
  std::partial_sort(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(n), order_.end());
  out.reason = "no keyframe verified";
  // Pending candidates are built here (and join the built ring after the loop, so that the ring
  // indices of the candidates stay valid while they are verified).
  built_now_.clear();
  int builds = 0;
  Status result = Status::ok();
  for (std::size_t i = 0; i < n && !out.found; ++i) {
    const Keyframe* cand = nullptr;
    if (order_[i].pending) {
      if (builds >= params_.max_builds_per_frame) continue;
      ++builds;
      Pending& p = pending_[order_[i].index];
      built_now_.emplace_back();
      Keyframe& kf = built_now_.back();
      kf.id = static_cast<int>(p.frame);
      kf.frame = p.frame;
      kf.T_world_cam = p.T_world_cam;
      kf.pose_cov = p.pose_cov;
      p.used = false;  // built or dropped: no longer pending
      const Status bs = builder_.process(p.left.cview(), p.dense, kf);
      if (!bs) {
        built_now_.pop_back();
        if (bs.code() == StatusCode::kFailedPrecondition) continue;  // too few ORB points
        result = bs;
        break;
      }
      cand = &kf;
    } else {
      cand = &ring_[order_[i].index];
    }
    const Keyframe& kf = *cand;
    LoopConstraint lc;
    if (Status vs = verifier_.process(query_, kf, lc); !vs) {
      result = vs;
      break;
    }
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
  }
  for (Keyframe& kf : built_now_) addToRing(kf);
  return result;
}

}  // namespace svslam

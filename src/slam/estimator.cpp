#include "slam/estimator.hpp"

#include "slam/slam_system.hpp"
#include "slam/vo_estimator.hpp"

namespace svslam {

Status VoEstimator::process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                            const StereoStageOutput& stereo, SlamFrameResult& out,
                            Executor& executor, StageObserver* observer) {
  (void)right;  // the stereo stage has matched the pair
  (void)executor;
  out = SlamFrameResult{};
  if (Status s = vo_.process(left, stereo, out.odometry, observer); !s) return s;
  out.T_world_cam = T_world_first_ * out.odometry.T_first_cam;
  out.pose_cov = out.odometry.covariance;
  return Status::ok();
}

Status VoEstimator::applyLoopCorrection(const Eigen::Isometry3d& C_new_old,
                                        const Matrix6d& cov_world, Eigen::Isometry3d& moved) {
  (void)cov_world;
  const Eigen::Matrix3d R = C_new_old.linear();
  if (!C_new_old.matrix().allFinite() ||
      !(R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || R.determinant() <= 0)
    return Status::invalidArgument("loop correction: C_new_old is not a finite rigid transform");
  T_world_first_ = C_new_old * T_world_first_;
  moved = C_new_old;
  return Status::ok();
}

std::unique_ptr<Estimator> makeEstimator(EstimatorKind kind, const SlamSystemParams& slam,
                                         const StereoOdometryParams& odometry,
                                         const StereoCalibration& calib) {
  if (kind == EstimatorKind::kVo) return std::make_unique<VoEstimator>(odometry, calib);
  if (kind == EstimatorKind::kMono)
    return std::make_unique<SlamSystem>(slam, odometry, calib, /*left_only=*/true);
  return std::make_unique<SlamSystem>(slam, odometry, calib);
}

FrameByFrame::FrameByFrame(const StereoOdometryParams& odometry, const StereoCalibration& calib,
                           std::unique_ptr<Estimator> estimator)
    : stage_(odometry, calib), estimator_(std::move(estimator)) {}

Status FrameByFrame::initStatus() const {
  if (!estimator_) return Status::invalidArgument("no estimator");
  if (Status s = stage_.initStatus(); !s) return s;
  return estimator_->initStatus();
}

Status FrameByFrame::process(ImageView<const std::uint8_t> left,
                             ImageView<const std::uint8_t> right, SlamFrameResult& out,
                             Executor& executor, StageObserver* observer) {
  if (Status s = initStatus(); !s) return s;
  if (Status s = stage_.process(left, right, estimator_->feedback(), stereo_, executor, observer);
      !s)
    return s;
  return estimator_->process(left, right, stereo_, out, executor, observer);
}

}  // namespace svslam

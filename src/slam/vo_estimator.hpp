#pragma once
// Pure stereo visual odometry as an Estimator: StereoOdometry's temporal matching and visual
// motion estimation with every match; the pose is the chained odometry, published with the last
// frame-to-frame motion's covariance (there is no pose covariance: EstimatorOutputs says so).
#include "slam/estimator.hpp"

namespace svslam {

class VoEstimator final : public Estimator {
 public:
  VoEstimator(const StereoOdometryParams& params, const StereoCalibration& calib)
      : vo_(params, calib) {}
  const Status& initStatus() const override { return vo_.initStatus(); }
  EstimatorOutputs outputs() const override { return {false, false}; }
  Status process(ImageView<const std::uint8_t> left, ImageView<const std::uint8_t> right,
                 const StereoStageOutput& stereo, SlamFrameResult& out, Executor& executor,
                 StageObserver* observer = nullptr) override;
  TrackingFeedback feedback() const override { return vo_.feedback(); }
  // T_world_first <- C_new_old T_world_first: the published pose is T_world_first T_first_cam.
  Status applyLoopCorrection(const Eigen::Isometry3d& C_new_old, const Matrix6d& cov_world,
                             Eigen::Isometry3d& moved) override;
  StereoOdometry& odometry() { return vo_; }

 private:
  StereoOdometry vo_;
  Eigen::Isometry3d T_world_first_ = Eigen::Isometry3d::Identity();
};

}  // namespace svslam

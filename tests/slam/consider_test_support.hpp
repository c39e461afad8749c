#pragma once
// Helpers of the consider-covariance tests (calibration_consider_test, drift_consider_test):
// poses from a rotation vector, and the rotation vector of an error rotation, as the
// evaluation takes it (log(R^ R^T)).
#include <Eigen/Geometry>

namespace svslam::consider_test {

inline Eigen::Isometry3d pose(const Eigen::Vector3d& rotvec, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (rotvec.norm() > 0)
    T.linear() = Eigen::AngleAxisd(rotvec.norm(), rotvec.normalized()).matrix();
  T.translation() = t;
  return T;
}

inline Eigen::Vector3d logRotation(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

}  // namespace svslam::consider_test

#pragma once
// The skew-symmetric matrix of a 3-vector: hatSO3(w) x = w x x (cross product), the Lie algebra
// element of SO(3) for the rotation vector w (rad).
#include <Eigen/Core>

namespace svslam {

inline Eigen::Matrix3d hatSO3(const Eigen::Vector3d& w) {
  Eigen::Matrix3d S;
  S << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return S;
}

}  // namespace svslam

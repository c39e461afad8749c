#pragma once
// The map frame (seed 001 sec 5.2, the definition): origin at the first left camera
// centre; z up, opposite to gravity; x the first camera's x axis projected on the horizontal
// plane; y = z x x. The world frame of the estimator is the first left camera's frame, so
//   p_map = R_map_world * p_world   (no translation: both have their origin at that centre).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

#include "core/status.hpp"

namespace svslam::map {

// R_map_world from the gravity direction in the first camera's frame (need not be unit length;
// must be finite, non-zero and not parallel to the camera's x axis). Error names the problem.
Status mapRotationFromGravity(const std::array<double, 3>& gravity_in_first_camera,
                              Eigen::Matrix3d& R_map_world);

}  // namespace svslam::map

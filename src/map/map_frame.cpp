// R_map_world from the gravity direction (map_frame.hpp).
#include "map/map_frame.hpp"

#include <cmath>
#include <string>

namespace svslam::map {

Status mapRotationFromGravity(const std::array<double, 3>& gravity_in_first_camera,
                              Eigen::Matrix3d& R_map_world) {
  const std::string key = "map.gravity_in_first_camera";
  const Eigen::Vector3d g(gravity_in_first_camera[0], gravity_in_first_camera[1],
                          gravity_in_first_camera[2]);
  if (!g.allFinite()) return Status::invalidArgument(key + " contains NaN or infinity");
  const double norm = g.norm();
  if (!(norm > 0.0)) return Status::invalidArgument(key + " is the zero vector");
  const Eigen::Vector3d z = -g / norm;  // up, in world (first camera) coordinates
  // The camera x axis without its vertical component.
  const Eigen::Vector3d x_proj = Eigen::Vector3d::UnitX() - z.x() * z;
  if (x_proj.norm() < 1e-6)
    return Status::invalidArgument(key + " is parallel to the first camera's x axis (the map x " +
                                   "axis, its horizontal projection, is undefined)");
  const Eigen::Vector3d x = x_proj.normalized();
  const Eigen::Vector3d y = z.cross(x);
  // Rows: the map axes in world coordinates, so R * p_world gives map coordinates.
  R_map_world.row(0) = x.transpose();
  R_map_world.row(1) = y.transpose();
  R_map_world.row(2) = z.transpose();
  return Status::ok();
}

}  // namespace svslam::map

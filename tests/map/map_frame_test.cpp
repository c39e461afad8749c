// The map frame from gravity: z up (against gravity), x the camera x axis made horizontal,
// a proper rotation; bad gravity vectors are rejected naming the key.
#include "map/map_frame.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using svslam::map::mapRotationFromGravity;

namespace {

void expectNear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double tol = 1e-12) {
  EXPECT_LT((a - b).norm(), tol) << "got " << a.transpose() << ", expected " << b.transpose();
}

void expectProperRotation(const Eigen::Matrix3d& R) {
  EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

}  // namespace

TEST(MapFrame, CameraLookingDown) {
  // Blimp: gravity along the optical axis. Up is the camera's -z; x stays the camera x.
  Eigen::Matrix3d R;
  ASSERT_TRUE(mapRotationFromGravity({0.0, 0.0, 1.0}, R));
  expectProperRotation(R);
  expectNear(R * Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(0, 0, 1));
  expectNear(R * Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 0, 0));
  // y_map = z x x = (0,0,-1) x (1,0,0) = (0,-1,0) in camera coordinates: image up.
  expectNear(R * Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 1, 0));
}

TEST(MapFrame, LevelForwardCamera) {
  // Car: gravity along image down. Up is the camera's -y, map y = z x x is the optical axis.
  Eigen::Matrix3d R;
  ASSERT_TRUE(mapRotationFromGravity({0.0, 1.0, 0.0}, R));
  expectProperRotation(R);
  expectNear(R * Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 1));
  expectNear(R * Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 0, 0));
  expectNear(R * Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 1, 0));
}

TEST(MapFrame, TiltedGravityNeedNotBeUnit) {
  const Eigen::Vector3d g(0.3, 0.5, 2.0);  // any length
  Eigen::Matrix3d R;
  ASSERT_TRUE(mapRotationFromGravity({g.x(), g.y(), g.z()}, R));
  expectProperRotation(R);
  // Gravity points straight down in the map.
  expectNear(R * g.normalized(), Eigen::Vector3d(0, 0, -1));
  // The camera x axis maps into the x-z plane of the map with a positive x component.
  const Eigen::Vector3d x_cam_in_map = R * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x_cam_in_map.y(), 0.0, 1e-12);
  EXPECT_GT(x_cam_in_map.x(), 0.0);
  // Same as the explicit construction.
  const Eigen::Vector3d z = -g.normalized();
  const Eigen::Vector3d x = (Eigen::Vector3d::UnitX() - z.x() * z).normalized();
  expectNear(R.row(0).transpose(), x);
  expectNear(R.row(1).transpose(), z.cross(x));
  expectNear(R.row(2).transpose(), z);
}

TEST(MapFrame, BadGravityIsNamed) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const std::array<double, 3>& g :
       {std::array<double, 3>{nan, 0.0, 1.0}, std::array<double, 3>{0.0, inf, 1.0},
        std::array<double, 3>{0.0, 0.0, 0.0}, std::array<double, 3>{1.0, 0.0, 0.0},
        std::array<double, 3>{-2.0, 1e-9, 0.0}}) {
    Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
    const svslam::Status s = mapRotationFromGravity(g, R);
    EXPECT_FALSE(s) << g[0] << " " << g[1] << " " << g[2];
    EXPECT_EQ(s.code(), svslam::StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("map.gravity_in_first_camera"), std::string::npos) << s.message();
  }
  // Just outside the parallel tolerance: a valid frame.
  Eigen::Matrix3d R;
  EXPECT_TRUE(mapRotationFromGravity({1.0, 1e-3, 0.0}, R));
}

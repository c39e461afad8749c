// The numbers behind svslam plot: nice ticks, 2-sigma ellipses of known covariances, the
// horizontal frame of KITTI (gravity +y) and of a down-looking camera (gravity +z).
#include "eval/plot_scales.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace svslam {
namespace {

TEST(NiceTicks, OneTwoFiveSteps) {
  Ticks t = niceTicks(0.0, 10.0, 6);
  EXPECT_DOUBLE_EQ(t.step, 2.0);
  ASSERT_EQ(t.values.size(), 6u);
  EXPECT_DOUBLE_EQ(t.values.front(), 0.0);
  EXPECT_DOUBLE_EQ(t.values.back(), 10.0);
  EXPECT_EQ(t.decimals, 0);

  t = niceTicks(-0.013, 0.087, 5);
  EXPECT_NEAR(t.step, 0.02, 1e-15);
  EXPECT_EQ(t.decimals, 2);
  for (double v : t.values) {
    EXPECT_GE(v, -0.013);
    EXPECT_LE(v, 0.087);
  }
  EXPECT_EQ(tickLabel(t.values.front(), t.decimals), "0.00");
  EXPECT_EQ(tickLabel(t.values.back(), t.decimals), "0.08");
}

TEST(NiceTicks, AtLeastTwoAndDegenerate) {
  const Ticks t = niceTicks(0.9, 1.1, 2);
  EXPECT_GE(t.values.size(), 2u);
  EXPECT_TRUE(niceTicks(1.0, 1.0).values.empty());
  EXPECT_TRUE(niceTicks(NAN, 1.0).values.empty());
  EXPECT_TRUE(niceTicks(2.0, 1.0).values.empty());
  EXPECT_EQ(tickLabel(-0.0001, 2), "0.00");
  EXPECT_EQ(tickLabel(-1.5, 1), "-1.5");
}

TEST(CovarianceEllipse, AxisAlignedAndRotated) {
  // diag(9, 1): sigmas 3 and 1, 2-sigma semi-axes 6 and 2 along x.
  auto e = covarianceEllipse(Eigen::Vector2d(9, 1).asDiagonal(), 2.0);
  ASSERT_TRUE(e.isOk());
  EXPECT_NEAR(e->a, 6.0, 1e-12);
  EXPECT_NEAR(e->b, 2.0, 1e-12);
  EXPECT_NEAR(e->angle_rad, 0.0, 1e-12);

  // The same turned by 30 degrees: C = R diag(9, 1) R^T.
  const Eigen::Matrix2d R = Eigen::Rotation2Dd(M_PI / 6).toRotationMatrix();
  const Eigen::Matrix2d C = R * Eigen::Vector2d(9, 1).asDiagonal() * R.transpose();
  e = covarianceEllipse(C, 2.0);
  ASSERT_TRUE(e.isOk());
  EXPECT_NEAR(e->a, 6.0, 1e-12);
  EXPECT_NEAR(e->b, 2.0, 1e-12);
  EXPECT_NEAR(e->angle_rad, M_PI / 6, 1e-12);

  // Every point of the outline is at Mahalanobis distance k from the centre.
  const Eigen::Vector2d c(5, -3);
  for (const auto& q : ellipsePoints(c, *e, 36))
    EXPECT_NEAR((q - c).dot(C.inverse() * (q - c)), 4.0, 1e-9);

  // Turned by -60 degrees (major axis along 120 degrees): angle in (-pi/2, pi/2].
  const Eigen::Matrix2d R2 = Eigen::Rotation2Dd(2 * M_PI / 3).toRotationMatrix();
  e = covarianceEllipse(R2 * Eigen::Vector2d(4, 1).asDiagonal() * R2.transpose(), 1.0);
  ASSERT_TRUE(e.isOk());
  EXPECT_NEAR(e->angle_rad, -M_PI / 3, 1e-12);
  EXPECT_NEAR(e->a, 2.0, 1e-12);
}

TEST(CovarianceEllipse, ZeroAndBadMatrices) {
  auto e = covarianceEllipse(Eigen::Matrix2d::Zero());
  ASSERT_TRUE(e.isOk());
  EXPECT_EQ(e->a, 0.0);
  Eigen::Matrix2d nan = Eigen::Matrix2d::Identity();
  nan(0, 1) = NAN;
  EXPECT_FALSE(covarianceEllipse(nan).isOk());
  Eigen::Matrix2d asym = Eigen::Matrix2d::Identity();
  asym(0, 1) = 0.5;
  EXPECT_FALSE(covarianceEllipse(asym).isOk());
  EXPECT_FALSE(covarianceEllipse(Eigen::Vector2d(1, -1).asDiagonal()).isOk());
}

TEST(HorizontalFrame, KittiAndDownLookingCamera) {
  auto f = horizontalFrame({0, 1, 0});  // KITTI: y down
  ASSERT_TRUE(f.isOk());
  EXPECT_EQ(f->u_name, "x");
  EXPECT_EQ(f->v_name, "z");
  EXPECT_EQ(f->up_name, "-y");
  EXPECT_TRUE(f->u.cross(f->v).isApprox(f->up));

  f = horizontalFrame({0, 0, 9.81});  // camera looking down
  ASSERT_TRUE(f.isOk());
  EXPECT_EQ(f->u_name, "x");
  EXPECT_EQ(f->v_name, "-y");
  EXPECT_EQ(f->up_name, "-z");
  EXPECT_TRUE(f->u.cross(f->v).isApprox(f->up));

  f = horizontalFrame({0.3, 1, 0.2});  // tilted: generic axes, still right-handed
  ASSERT_TRUE(f.isOk());
  EXPECT_EQ(f->u_name, "u");
  EXPECT_NEAR(f->u.dot(f->up), 0.0, 1e-12);
  EXPECT_NEAR(f->v.dot(f->up), 0.0, 1e-12);
  EXPECT_TRUE(f->u.cross(f->v).isApprox(f->up));
  EXPECT_NEAR(f->up.dot(Eigen::Vector3d(0.3, 1, 0.2).normalized()), -1.0, 1e-12);

  EXPECT_FALSE(horizontalFrame(Eigen::Vector3d::Zero()).isOk());
  EXPECT_FALSE(horizontalFrame({NAN, 1, 0}).isOk());
}

}  // namespace
}  // namespace svslam

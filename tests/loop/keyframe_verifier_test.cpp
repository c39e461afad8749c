// Keyframes and geometric verification on a rendered flight with exact ground truth: a place
// seen again on the second lap is verified with the true relative pose within its covariance;
// places that do not overlap are refused; the keyframe rule and memory bound hold.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "drivers/synthetic/synthetic_flight.hpp"
#include "loop/keyframe.hpp"
#include "loop/loop_verifier.hpp"
#include "stereo/dense_stereo.hpp"

using namespace svslam;

namespace {

// A 512x384 blimp flight over a 100 m loop flown twice (100 frames a lap).
drivers::SyntheticFlightParams flightParams() {
  drivers::SyntheticFlightParams p;
  p.width = 512;
  p.height = 384;
  p.frames = 200;
  p.loop_frames = 100;
  p.loop_length_m = 100;
  return p;
}

class KeyframeVerifierTest : public ::testing::Test {
 protected:
  KeyframeVerifierTest() : flight_(flightParams()) {
    DenseStereoParams dp;
    dp.max_disp = 64;
    dense_ = std::make_unique<DenseStereo>(dp, flight_.params().width, flight_.params().height);
  }
  Keyframe make(int frame, int id) {
    ImageU8 l, r;
    EXPECT_TRUE(flight_.render(frame, l, r).isOk());
    DisparityResult d;
    EXPECT_TRUE(dense_->process(l.cview(), r.cview(), d).isOk());
    KeyframeBuilder b(KeyframeParams{}, flight_.calibration());
    EXPECT_TRUE(b.initStatus().isOk()) << b.initStatus().message();
    Keyframe k;
    k.id = id;
    k.frame = frame;
    k.T_world_cam = flight_.pose(frame);
    const Status s = b.process(l.cview(), d, k);
    EXPECT_TRUE(s.isOk()) << s.message();
    return k;
  }
  drivers::SyntheticFlight flight_;
  std::unique_ptr<DenseStereo> dense_;
};

double angleDeg(const Eigen::Matrix3d& R) {
  return Eigen::AngleAxisd(R).angle() * 180.0 / 3.14159265358979323846;
}

TEST_F(KeyframeVerifierTest, RevisitIsVerifiedWithTheTrueMotionWithinItsCovariance) {
  const Keyframe a = make(4, 0);    // first lap
  const Keyframe b = make(105, 1);  // second lap, one frame (1 m) further along
  EXPECT_GE(a.size(), 200u);
  EXPECT_LE(a.size(), 400u);
  EXPECT_LE(a.bytes(), 40u * 1024u);
  LoopVerifier v(LoopVerifierParams{});
  ASSERT_TRUE(v.initStatus().isOk());
  LoopConstraint c;
  ASSERT_TRUE(v.process(b, a, c).isOk());
  EXPECT_TRUE(c.accepted) << c.reason << " matches " << c.matches << " inliers " << c.inliers;
  EXPECT_GE(c.inliers, 50);
  const Eigen::Isometry3d T_true = flight_.pose(105).inverse() * flight_.pose(4);
  const Eigen::Isometry3d E = T_true.inverse() * c.T_query_candidate;
  EXPECT_LT(E.translation().norm(), 0.05);
  EXPECT_LT(angleDeg(E.linear()), 0.2);
  // Normalised error within the covariance (chi2 6 dof, 99.9 % = 22.5).
  Eigen::Matrix<double, 6, 1> r;
  r.head<3>() = logSO3(c.T_query_candidate.linear() * T_true.linear().transpose());
  r.tail<3>() = c.T_query_candidate.translation() - T_true.translation();
  const double nees = r.dot(c.covariance.ldlt().solve(r));
  EXPECT_LT(nees, 22.5) << "error " << r.transpose();
}

TEST_F(KeyframeVerifierTest, PlacesThatDoNotOverlapAreRefused) {
  const Keyframe a = make(4, 0);
  const Keyframe far = make(50, 1);  // the other side of the loop, no common ground
  LoopVerifier v(LoopVerifierParams{});
  LoopConstraint c;
  ASSERT_TRUE(v.process(far, a, c).isOk());
  EXPECT_FALSE(c.accepted) << "inliers " << c.inliers << " of " << c.matches;
  EXPECT_FALSE(c.reason.empty());
}

TEST_F(KeyframeVerifierTest, SelectorFollowsTravelAndRotation) {
  KeyframeParams p;
  KeyframeSelector s(p);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  EXPECT_TRUE(s.isKeyframe(T));
  s.accept(T, 27.0);  // next keyframe after 2.7 m
  T.translation() = Eigen::Vector3d(2.6, 0, 0);
  EXPECT_FALSE(s.isKeyframe(T));
  T.translation() = Eigen::Vector3d(0, 2.71, 0);
  EXPECT_TRUE(s.isKeyframe(T));
  T.translation().setZero();
  T.linear() = Eigen::AngleAxisd(0.27, Eigen::Vector3d::UnitZ()).toRotationMatrix();  // 15.5 deg
  EXPECT_TRUE(s.isKeyframe(T));
}

TEST(KeyframeParamsTest, BadValuesAreNamed) {
  KeyframeParams p;
  p.max_points = 3;
  EXPECT_NE(p.validate().message().find("max_points"), std::string::npos);
  p = KeyframeParams{};
  p.travel_depth_fraction = std::nan("");
  EXPECT_FALSE(p.validate().isOk());
  LoopVerifierParams v;
  v.max_ratio = 0;
  EXPECT_NE(v.validate().message().find("max_ratio"), std::string::npos);
}

TEST(KeyframeBuilderTest, WrongSizeIsAnError) {
  StereoCalibration c{400, 255.5, 191.5, 2.2, 512, 384};
  KeyframeBuilder b(KeyframeParams{}, c);
  ASSERT_TRUE(b.initStatus().isOk());
  ImageU8 l(100, 100);
  DisparityResult d;
  Keyframe k;
  EXPECT_EQ(b.process(l.cview(), d, k).code(), StatusCode::kInvalidArgument);
}

}  // namespace

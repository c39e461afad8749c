// Relocalisation after a real loss (slam/relocaliser.hpp): keyframes kept from the rendered
// blimp flight (512 x 384, 100 frames over one 300 m loop, 3 m a frame); a frame seen again
// near them is found from a prediction metres off, a frame over ground no keyframe saw (the
// other side of the loop, 77 m and more away) is not (no false relocalisation), a black frame
// is not; the ring keeps its bound. Then the whole filter: both
// cameras black from frame 40 to 50 (one second at 10 Hz, flown as a camera loss on the
// constant-velocity prediction): with relocalisation the pose comes back at the first frame
// with images, without it the filter never finds its map again.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "drivers/source/stereo_source.hpp"
#include "drivers/synthetic/synthetic_flight.hpp"
#include "slam/relocaliser.hpp"
#include "slam/slam_system.hpp"
#include "stereo/dense_stereo.hpp"

namespace svslam {
namespace {

drivers::SyntheticFlightParams flightParams() {
  drivers::SyntheticFlightParams p;
  p.width = 512;
  p.height = 384;
  p.frames = 100;
  p.loop_length_m = 300;
  return p;
}

class RelocaliserTest : public ::testing::Test {
 protected:
  RelocaliserTest() : flight_(flightParams()) {}
  // Frame `frame` rendered with its dense disparity into l_ and d_ (each frame rendered once
  // for the whole suite: the renderer is most of this test's time).
  void render(int frame) {
    auto it = cache().find(frame);
    if (it == cache().end()) {
      static std::unique_ptr<DenseStereo> dense =
          std::make_unique<DenseStereo>(DenseStereoParams{}, 512, 384);
      Rendered r;
      ImageU8 right;
      EXPECT_TRUE(flight_.render(frame, r.left, right).isOk());
      EXPECT_TRUE(dense->process(r.left.cview(), right.cview(), r.dense).isOk());
      it = cache().emplace(frame, std::move(r)).first;
    }
    l_ = it->second.left.cview();
    d_ = &it->second.dense;
  }
  // T_first_cam of the ground truth (the filter's world is the first camera).
  Eigen::Isometry3d truth(int frame) const { return flight_.pose(0).inverse() * flight_.pose(frame); }
  // Keyframes offered from frames 0..last at their true poses (pose sigma 1 cm, 1 mrad).
  void keep(Relocaliser& r, int last) {
    Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
    cov.diagonal() << 1e-6, 1e-6, 1e-6, 1e-4, 1e-4, 1e-4;
    for (int k = 0; k <= last; ++k) {
      render(k);
      bool kept = false;
      ASSERT_TRUE(r.offer(l_, *d_, truth(k), cov, k, kept).isOk());
    }
  }
  struct Rendered {
    ImageU8 left;
    DisparityResult dense;
  };
  static std::map<int, Rendered>& cache() {
    static std::map<int, Rendered> c;
    return c;
  }
  drivers::SyntheticFlight flight_;
  ImageView<const std::uint8_t> l_;  // the frame last rendered and its dense disparity
  const DisparityResult* d_ = nullptr;
};

// Both ways of keeping keyframes: built when kept (pending_keyframes 0), and pending (the
// default: built when the lost frame needs them).
TEST_F(RelocaliserTest, LostFrameIsFoundAgainstTheKeptKeyframes) {
  for (int pending : {0, 4}) {
  SCOPED_TRACE("pending_keyframes " + std::to_string(pending));
  RelocaliserParams p;
  p.pending_keyframes = pending;
  Relocaliser reloc(p, flight_.calibration());
  ASSERT_TRUE(reloc.initStatus().isOk()) << reloc.initStatus().message();
  keep(reloc, 30);
  if (pending == 0) {
    EXPECT_GE(reloc.keyframes(), 5);
    EXPECT_EQ(reloc.pendingKeyframes(), 0);
  } else {
    EXPECT_EQ(reloc.keyframes(), 0);  // nothing built while tracking
    EXPECT_EQ(reloc.pendingKeyframes(), pending);
  }
  for (int frame : {32, 35}) {
    render(frame);
    Eigen::Isometry3d pred = truth(frame);
    pred.translation() += Eigen::Vector3d(6.0, -4.0, 1.0);  // the prediction after a loss
    RelocalisationResult out;
    ASSERT_TRUE(reloc.relocalise(l_, *d_, pred, frame, out).isOk());
    ASSERT_TRUE(out.found) << "frame " << frame << ": " << out.reason;
    const Eigen::Isometry3d T = truth(frame);
    const double dt = (out.T_world_cam.translation() - T.translation()).norm();
    const double dr =
        Eigen::AngleAxisd(out.T_world_cam.linear() * T.linear().transpose()).angle() * 180 / M_PI;
    Eigen::Matrix<double, 6, 1> e;
    const Eigen::AngleAxisd aa(T.linear() * out.T_world_cam.linear().transpose());
    e.head<3>() = aa.angle() * aa.axis();
    e.tail<3>() = T.translation() - out.T_world_cam.translation();
    const double nees = e.dot(out.covariance.ldlt().solve(e));
    std::printf("frame %d relocalised against keyframe %lld: %d inliers, %d tried, error %.3f m "
                "%.3f deg, NEES %.2f\n",
                frame, static_cast<long long>(out.keyframe_frame), out.inliers,
                out.candidates_tried, dt, dr, nees);
    EXPECT_LT(dt, 0.2);  // one 3D-3D constraint at 27 m; the filter's landmarks refine it
    EXPECT_LT(dr, 0.2);
    EXPECT_LT(nees, 22.46);  // chi2, 6 dof, 99.9 %
  }
  if (pending > 0) {  // the candidates tried were built and kept, the others still pending
    EXPECT_GE(reloc.keyframes(), 1);
    EXPECT_EQ(reloc.keyframes() + reloc.pendingKeyframes(), pending);
  }
  }
}

TEST_F(RelocaliserTest, NoPoseWhereNoKeyframeSawTheGroundOrInABlackFrame) {
  Relocaliser reloc(RelocaliserParams{}, flight_.calibration());
  ASSERT_TRUE(reloc.initStatus().isOk());
  RelocalisationResult out;
  render(10);
  ASSERT_TRUE(reloc.relocalise(l_, *d_, truth(10), 10, out).isOk());
  EXPECT_FALSE(out.found);
  EXPECT_STREQ(out.reason, "no keyframe kept yet");
  keep(reloc, 20);
  // The other side of the loop: the ground the first 20 frames saw is out of view.
  for (int frame : {50, 60, 70}) {
    render(frame);
    ASSERT_TRUE(reloc.relocalise(l_, *d_, truth(20), frame, out).isOk());
    EXPECT_FALSE(out.found) << "frame " << frame << " against keyframe " << out.keyframe_frame;
    EXPECT_GT(out.candidates_tried, 0);
  }
  ImageU8 black(512, 384);
  black.fill(0);
  DenseStereo dense(DenseStereoParams{}, 512, 384);
  DisparityResult black_dense;
  ASSERT_TRUE(dense.process(black.cview(), black.cview(), black_dense).isOk());
  l_ = black.cview();
  d_ = &black_dense;
  ASSERT_TRUE(reloc.relocalise(l_, *d_, truth(20), 21, out).isOk());
  EXPECT_FALSE(out.found);
  EXPECT_STREQ(out.reason, "too few points in the frame");
}

TEST_F(RelocaliserTest, RingKeepsItsBoundAndBadInputIsNamed) {
  RelocaliserParams p;
  p.max_keyframes = 3;
  p.pending_keyframes = 0;  // every keyframe built into the ring of 3
  Relocaliser reloc(p, flight_.calibration());
  ASSERT_TRUE(reloc.initStatus().isOk());
  keep(reloc, 40);
  EXPECT_EQ(reloc.keyframes(), 3);
  // The newest keyframes are the ones kept: frame 38 is found.
  render(38);
  RelocalisationResult out;
  ASSERT_TRUE(reloc.relocalise(l_, *d_, truth(38), 38, out).isOk());
  EXPECT_TRUE(out.found) << out.reason;
  EXPECT_GE(out.keyframe_frame, 25);

  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.translation().x() = NAN;
  EXPECT_EQ(reloc.relocalise(l_, *d_, bad, 39, out).code(), StatusCode::kInvalidArgument);
  bool kept = false;
  EXPECT_EQ(reloc.offer(l_, *d_, bad, Eigen::Matrix<double, 6, 6>::Zero(), 39, kept).code(),
            StatusCode::kInvalidArgument);
  // A pending keyframe is copied: a disparity of another size is named, nothing kept.
  Relocaliser lazy(RelocaliserParams{}, flight_.calibration());
  DisparityResult small;
  small.disparity_px.resize(8, 8);
  small.sigma_d_px.resize(8, 8);
  const Status s = lazy.offer(l_, small, truth(39), Eigen::Matrix<double, 6, 6>::Zero(), 39, kept);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("calibration size"), std::string::npos) << s.message();
  EXPECT_EQ(lazy.pendingKeyframes(), 0);
  for (auto mutate : {+[](RelocaliserParams& q) { q.max_keyframes = 0; },
                      +[](RelocaliserParams& q) { q.max_candidates = 0; },
                      +[](RelocaliserParams& q) { q.max_lost_frames = 0; },
                      +[](RelocaliserParams& q) { q.pending_keyframes = -1; },
                      +[](RelocaliserParams& q) { q.pending_keyframes = 101; },
                      +[](RelocaliserParams& q) { q.max_builds_per_frame = 0; },
                      +[](RelocaliserParams& q) { q.verify.min_inliers = 2; }}) {
    RelocaliserParams q;
    mutate(q);
    const Status s = q.validate();
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("relocalisation"), std::string::npos) << s.message();
  }
}

struct LossRun {
  double final_error_m = 0, error_at_55_m = 0;
  int lost = 0, relocalised = 0, without_motion_or_relocalisation = 0;
};

// The whole flight through the filter, both cameras black in frames [40, 50).
LossRun runFilter(bool relocalise, int last_frame = 69) {
  LossRun r;
  auto src = drivers::openStereoSource(
      "synthetic:width=512,height=384,frames=70,black_from=40,black_to=50");
  EXPECT_TRUE(src.isOk()) << src.status().message();
  if (!src) return r;
  const StereoCalibration calib = (*src)->calibration();
  SlamSystemParams sp;
  sp.relocalisation.enabled = relocalise;
  StereoOdometryParams op;
  op.dense = true;  // the keyframes' 3D points (as in svslam run)
  FrameByFrame slam(op, calib, std::make_unique<SlamSystem>(sp, op, calib));
  EXPECT_TRUE(slam.initStatus().isOk()) << slam.initStatus().message();
  SerialExecutor ex;
  drivers::StereoFrame f;
  for (int k = 0;; ++k) {
    auto more = (*src)->next(f);
    EXPECT_TRUE(more.isOk()) << more.status().message();
    if (!more || !*more || k > last_frame) break;
    SlamFrameResult out;
    const Status s = slam.process(f.left.cview(), f.right.cview(), out, ex);
    EXPECT_TRUE(s.isOk()) << "frame " << k << ": " << s.message();
    EXPECT_TRUE(out.T_world_cam.matrix().allFinite()) << "frame " << k;
    EXPECT_TRUE(out.pose_cov.allFinite()) << "frame " << k;
    r.lost += out.lost ? 1 : 0;
    r.relocalised += out.relocalised ? 1 : 0;
    if (k >= 50 && !out.odometry.tracked && !out.relocalised && !out.mono)
      ++r.without_motion_or_relocalisation;
    Eigen::Isometry3d g;
    EXPECT_TRUE((*src)->groundTruth(f.index, g));
    const double e = (g.translation() - out.T_world_cam.translation()).norm();
    if (k == 55) r.error_at_55_m = e;
    r.final_error_m = e;
  }
  return r;
}

TEST(RelocalisationInTheFilter, BothCamerasBlackForOneSecond) {
  const LossRun with = runFilter(true), without = runFilter(false, 55);
  std::printf("both cameras black, frames 40-49: with relocalisation %d lost frames, %d "
              "relocalised, error at frame 55 %.3f m, final %.3f m; without: error at 55 %.3f m\n",
              with.lost, with.relocalised, with.error_at_55_m, with.final_error_m,
              without.error_at_55_m);
  // The black frames are flown as a camera loss (the right image is flat: bearings of the map,
  // none found in a black left image); the first frame with images has no motion (its previous
  // frame is black) and is relocalised.
  EXPECT_GE(with.lost, 1);
  EXPECT_GE(with.relocalised, 1);
  EXPECT_EQ(with.without_motion_or_relocalisation, 0);
  EXPECT_LT(with.error_at_55_m, 0.15);
  EXPECT_LT(with.final_error_m, 0.1);
  EXPECT_GT(without.error_at_55_m, 1.0);  // what relocalisation is for
}

}  // namespace
}  // namespace svslam

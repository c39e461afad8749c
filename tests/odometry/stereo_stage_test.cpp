// The stereo stage (dense stereo, points, ROIs, stereo matching, 3D points) as the pipeline runs
// it: in two halves around the estimator's feedback, or in one call, with the same output; and
// the estimators behind the one Estimator interface.
#include "odometry/stereo_stage.hpp"

#include <gtest/gtest.h>

#include "drivers/source/stereo_source.hpp"
#include "odometry/stereo_odometry.hpp"
#include "slam/estimator.hpp"
#include "slam/slam_system.hpp"
#include "slam/vo_estimator.hpp"

namespace svslam {
namespace {

struct Variant {
  const char* name;
  StereoOdometryParams params;
};

std::vector<Variant> variants() {
  std::vector<Variant> v;
  v.push_back({"corners", StereoOdometryParams{}});
  StereoOdometryParams orb;
  orb.detector = PointDetector::kOrb;
  v.push_back({"orb", orb});
  StereoOdometryParams dense;
  dense.dense = true;
  dense.dense_stereo.max_disp = 64;
  v.push_back({"dense", dense});
  StereoOdometryParams roi;
  roi.roi_tracking = true;
  v.push_back({"roi", roi});
  return v;
}

bool samePoints(const std::vector<TrackPoint>& a, const std::vector<TrackPoint>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].u_px != b[i].u_px || a[i].v_px != b[i].v_px || a[i].p_cam != b[i].p_cam ||
        a[i].cov != b[i].cov || a[i].d_px != b[i].d_px)
      return false;
  return true;
}

TEST(StereoStage, HalvesEqualOneCallAndRoisFollowTheFeedback) {
  for (const Variant& var : variants()) {
    // The first 6 frames of a 100-frame flight (about 20 px of motion a frame).
    auto src = drivers::openStereoSource("synthetic:width=384,height=288,frames=100");
    ASSERT_TRUE(src.isOk());
    const StereoCalibration calib = (*src)->calibration();
    StereoStage one(var.params, calib), halves(var.params, calib);
    StereoOdometry vo(var.params, calib);
    ASSERT_TRUE(one.initStatus().isOk()) << var.name << ": " << one.initStatus().message();
    EXPECT_EQ(one.needsFeedback(), var.params.roi_tracking);
    StereoStageOutput a, b;
    SerialExecutor ex;
    drivers::StereoFrame f;
    int n = 0, with_rois = 0;
    while (n < 6) {
      auto more = (*src)->next(f);
      ASSERT_TRUE(more.isOk() && more.value());
      const auto l = f.left.cview(), r = f.right.cview();
      const TrackingFeedback fb = vo.feedback();
      EXPECT_EQ(fb.has_previous, n > 0) << var.name;
      ASSERT_TRUE(one.process(l, r, fb, a, ex).isOk());
      ASSERT_TRUE(halves.prepare(l, r, b, ex).isOk());
      EXPECT_FALSE(b.finished);
      ASSERT_TRUE(halves.finish(l, r, fb, b).isOk());
      EXPECT_TRUE(a.finished && b.finished);
      EXPECT_EQ(a.has_disparity, var.params.dense) << var.name;
      EXPECT_EQ(a.corner_px, b.corner_px) << var.name << " frame " << n;
      EXPECT_TRUE(samePoints(a.points, b.points)) << var.name << " frame " << n;
      EXPECT_EQ(a.prev_regions, b.prev_regions) << var.name;
      EXPECT_GT(a.points.size(), 50u) << var.name;
      with_rois += a.has_rois ? 1 : 0;
      OdometryFrameResult r_out;
      ASSERT_TRUE(vo.process(l, a, r_out).isOk());
      EXPECT_TRUE(r_out.tracked) << var.name << " frame " << n << ": " << r_out.failure;
      EXPECT_EQ(r_out.stereo_points, static_cast<int>(a.points.size()));
      ++n;
    }
    EXPECT_EQ(n, 6);
    // ROIs from the second frame on (the first has no previous clusters), never without them.
    EXPECT_EQ(with_rois, var.params.roi_tracking ? 5 : 0) << var.name;
  }
}

// A pooled output sized by prepareOutput() is not reallocated by its first frame: the dense
// images and the point vectors keep their buffers (the first pass of a pipeline slot costs what
// the later ones cost), and the result is the one an unprepared output gets.
TEST(StereoStage, PreparedOutputKeepsItsBuffersThroughTheFirstFrame) {
  auto src = drivers::openStereoSource("synthetic:width=384,height=288,frames=1");
  ASSERT_TRUE(src.isOk());
  const StereoCalibration calib = (*src)->calibration();
  StereoOdometryParams params;
  params.dense = true;
  params.dense_stereo.max_disp = 64;
  StereoStage stage(params, calib);
  ASSERT_TRUE(stage.initStatus().isOk());
  StereoStageOutput prepared, fresh;
  stage.prepareOutput(prepared);
  ASSERT_EQ(prepared.disparity.disparity_px.width(), calib.width);
  ASSERT_EQ(prepared.disparity.curvature.height(), calib.height);
  const float* disparity = prepared.disparity.disparity_px.row(0);
  const float* sigma = prepared.disparity.sigma_d_px.row(0);
  const std::size_t capacity = prepared.points.capacity();
  EXPECT_GT(capacity, 0u);
  const TrackPoint* points = prepared.points.data();
  const Eigen::Vector2f* corners = prepared.corner_px.data();
  drivers::StereoFrame f;
  auto more = (*src)->next(f);
  ASSERT_TRUE(more.isOk() && more.value());
  SerialExecutor ex;
  ASSERT_TRUE(stage.process(f.left.cview(), f.right.cview(), {}, prepared, ex).isOk());
  EXPECT_GT(prepared.points.size(), 50u);
  EXPECT_LE(prepared.points.size(), capacity);
  EXPECT_EQ(prepared.disparity.disparity_px.row(0), disparity);
  EXPECT_EQ(prepared.disparity.sigma_d_px.row(0), sigma);
  EXPECT_EQ(prepared.points.data(), points);
  EXPECT_EQ(prepared.corner_px.data(), corners);
  StereoStage twin(params, calib);
  ASSERT_TRUE(twin.process(f.left.cview(), f.right.cview(), {}, fresh, ex).isOk());
  EXPECT_TRUE(samePoints(prepared.points, fresh.points));
  EXPECT_EQ(prepared.disparity.stats.valid, fresh.disparity.stats.valid);
}

TEST(StereoStage, RejectsWrongSizeAndMismatchedOutput) {
  auto src = drivers::openStereoSource("synthetic:width=256,height=192,frames=1");
  ASSERT_TRUE(src.isOk());
  const StereoCalibration calib = (*src)->calibration();
  StereoStage stage(StereoOdometryParams{}, calib);
  ImageU8 small(128, 96);
  StereoStageOutput out;
  SerialExecutor ex;
  EXPECT_FALSE(stage.process(small.cview(), small.cview(), {}, out, ex).isOk());
  drivers::StereoFrame f;
  auto more = (*src)->next(f);
  ASSERT_TRUE(more.isOk() && more.value());
  // Only the first half run: refused by the odometry, not misused.
  ASSERT_TRUE(stage.prepare(f.left.cview(), f.right.cview(), out, ex).isOk());
  StereoOdometry plain(StereoOdometryParams{}, calib);
  OdometryFrameResult r;
  EXPECT_FALSE(plain.frontEnd(f.left.cview(), out, r).isOk());
  // An output made without dense stereo given to a dense odometry.
  ASSERT_TRUE(stage.finish(f.left.cview(), f.right.cview(), {}, out).isOk());
  EXPECT_TRUE(plain.frontEnd(f.left.cview(), out, r).isOk());
  StereoOdometryParams dense;
  dense.dense = true;
  dense.dense_stereo.max_disp = 64;
  StereoOdometry vo(dense, calib);
  EXPECT_FALSE(vo.frontEnd(f.left.cview(), out, r).isOk());
}

// Both modes behind the one interface: what each produces, and the VO estimator is the odometry
// (same poses as StereoOdometry driven by hand).
TEST(Estimator, ModesBehindOneInterface) {
  auto src = drivers::openStereoSource("synthetic:width=384,height=288,frames=100");
  ASSERT_TRUE(src.isOk());
  const StereoCalibration calib = (*src)->calibration();
  const StereoOdometryParams p;
  auto ekf = makeEstimator(EstimatorKind::kEkf, SlamSystemParams{}, p, calib);
  auto vo = makeEstimator(EstimatorKind::kVo, SlamSystemParams{}, p, calib);
  ASSERT_TRUE(ekf->initStatus().isOk() && vo->initStatus().isOk());
  EXPECT_TRUE(ekf->outputs().pose_covariance && ekf->outputs().landmark_map);
  EXPECT_FALSE(vo->outputs().pose_covariance || vo->outputs().landmark_map);
  FrameByFrame run_ekf(p, calib, std::move(ekf)), run_vo(p, calib, std::move(vo));
  StereoStage stage(p, calib);
  StereoStageOutput st;
  StereoOdometry by_hand(p, calib);
  SerialExecutor ex;
  drivers::StereoFrame f;
  int n = 0;
  while (n < 5 && (*src)->next(f).value()) {
    const auto l = f.left.cview(), r = f.right.cview();
    SlamFrameResult e, v;
    ASSERT_TRUE(run_ekf.process(l, r, e, ex).isOk());
    ASSERT_TRUE(run_vo.process(l, r, v, ex).isOk());
    ASSERT_TRUE(stage.process(l, r, by_hand.feedback(), st, ex).isOk());
    OdometryFrameResult h;
    ASSERT_TRUE(by_hand.process(l, st, h).isOk());
    EXPECT_TRUE(v.T_world_cam.matrix() == h.T_first_cam.matrix()) << "frame " << n;
    EXPECT_TRUE(v.pose_cov == h.covariance);
    EXPECT_EQ(v.landmarks_in_map, 0);
    if (n > 0) {
      EXPECT_GT(e.landmarks_in_state + e.candidates, 0);
    }
    EXPECT_LT((e.T_world_cam.translation() - v.T_world_cam.translation()).norm(), 0.05);
    ++n;
  }
  EXPECT_EQ(n, 5);
  EXPECT_TRUE(run_vo.estimator().map().empty());
}

// An empty right view (the right camera lost, v4l2 right_loss=left_only): the stage gives the
// left corners and nothing that needs the right image; the ekf estimator flies on (a mono
// frame, finite pose), the vo estimator reports the frame untracked without failing.
TEST(StereoStage, EmptyRightViewGivesCornersOnly) {
  auto src = drivers::openStereoSource("synthetic:width=384,height=288,frames=8");
  ASSERT_TRUE(src.isOk());
  const StereoCalibration calib = (*src)->calibration();
  StereoOdometryParams p;
  p.dense = true;
  p.dense_stereo.max_disp = 64;
  StereoStage stage(p, calib);
  StereoStageOutput out;
  SerialExecutor ex;
  drivers::StereoFrame f;
  ASSERT_TRUE((*src)->next(f).value());
  const ImageView<const std::uint8_t> none;
  ASSERT_TRUE(stage.process(f.left.cview(), none, {}, out, ex).isOk());
  EXPECT_GT(out.corner_px.size(), 50u);
  EXPECT_FALSE(out.has_disparity);
  EXPECT_TRUE(out.points.empty());
  EXPECT_TRUE(out.stereo.empty());
  // A right view of the wrong size is still an error.
  ImageU8 small(10, 10);
  EXPECT_FALSE(stage.process(f.left.cview(), small.cview(), {}, out, ex).isOk());

  FrameByFrame ekf(p, calib, makeEstimator(EstimatorKind::kEkf, SlamSystemParams{}, p, calib));
  FrameByFrame vo(p, calib, makeEstimator(EstimatorKind::kVo, SlamSystemParams{}, p, calib));
  SlamFrameResult e, v;
  for (int k = 0; k < 8; ++k) {
    if (k > 0) {
      ASSERT_TRUE((*src)->next(f).value());
    }
    if (k < 4) {  // both cameras
      ASSERT_TRUE(ekf.process(f.left.cview(), f.right.cview(), e, ex).isOk());
      ASSERT_TRUE(vo.process(f.left.cview(), f.right.cview(), v, ex).isOk());
      continue;
    }
    ASSERT_TRUE(ekf.process(f.left.cview(), none, e, ex).isOk()) << "frame " << k;
    EXPECT_TRUE(e.mono);
    EXPECT_EQ(e.right_camera, static_cast<int>(RightCameraState::kMissing));
    EXPECT_TRUE(e.T_world_cam.matrix().allFinite());
    ASSERT_TRUE(vo.process(f.left.cview(), none, v, ex).isOk()) << "frame " << k;
    EXPECT_FALSE(v.odometry.tracked);
    EXPECT_TRUE(v.T_world_cam.matrix().allFinite());
  }
}

}  // namespace
}  // namespace svslam

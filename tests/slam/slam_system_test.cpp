// The EKF SLAM system on rendered flights with exact ground truth and on real data: loop
// closure against pure odometry, errors inside the filter's own 2 sigma, bounded landmark count,
// determinism. Real-data cases skip with a message when ../shared/data is absent.
#include "slam/slam_system.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <tuple>
#include <string>
#include <vector>

#include "drivers/source/stereo_source.hpp"
#include "slam/vo_estimator.hpp"
#include "drivers/files/trajectory_io.hpp"
#include "eval/trajectory_metrics.hpp"

namespace fs = std::filesystem;
using namespace svslam;

namespace {

struct RunOut {
  std::vector<Eigen::Isometry3d> est, vo, gt;
  std::vector<Matrix6d> cov;
  std::vector<Matrix6d> cov_consider;
  std::vector<TimeNs> t_ns;
  int max_in_state = 0;
  int reperceived = 0;
  int restored = 0;  // anchored landmarks put back into the state
  std::vector<int> in_map;  // landmarks in the map after each frame
  std::vector<MapLandmark> map;
};

// `inexact`: the source's calibration taken as not exact (its uncertainty is then published).
RunOut runSlam(const std::string& spec, const SlamSystemParams& sp, int max_frames = 0,
               bool inexact = false) {
  RunOut r;
  auto src = drivers::openStereoSource(spec);
  EXPECT_TRUE(src.isOk()) << src.status().message();
  if (!src) return r;
  StereoCalibration calib = (*src)->calibration();
  if (inexact) calib.exact = false;
  FrameByFrame slam(StereoOdometryParams{}, calib,
                    std::make_unique<SlamSystem>(sp, StereoOdometryParams{}, calib));
  EXPECT_TRUE(slam.initStatus().isOk()) << slam.initStatus().message();
  SerialExecutor ex;
  drivers::StereoFrame f;
  while (max_frames <= 0 || static_cast<int>(r.est.size()) < max_frames) {
    auto more = (*src)->next(f);
    EXPECT_TRUE(more.isOk()) << more.status().message();
    if (!more || !*more) break;
    SlamFrameResult out;
    EXPECT_TRUE(slam.process(f.left.cview(), f.right.cview(), out, ex).isOk());
    EXPECT_TRUE(out.T_world_cam.matrix().allFinite());
    r.est.push_back(out.T_world_cam);
    r.vo.push_back(out.odometry.T_first_cam);
    r.cov.push_back(out.pose_cov);
    r.cov_consider.push_back(out.pose_cov_consider);
    r.t_ns.push_back(f.t_ns);
    r.max_in_state = std::max(r.max_in_state, out.landmarks_in_state);
    r.reperceived += out.reperceived;
    r.restored += out.restored;
    r.in_map.push_back(out.landmarks_in_map);
    Eigen::Isometry3d g;
    if ((*src)->groundTruth(f.index, g)) r.gt.push_back(g);
  }
  r.map = slam.estimator().map();
  return r;
}

// Pure visual odometry on the same source (the `--mode vo` baseline).
std::vector<Eigen::Isometry3d> runVo(const std::string& spec) {
  std::vector<Eigen::Isometry3d> out;
  auto src = drivers::openStereoSource(spec);
  EXPECT_TRUE(src.isOk());
  if (!src) return out;
  const StereoCalibration calib = (*src)->calibration();
  FrameByFrame vo(StereoOdometryParams{}, calib,
                  std::make_unique<VoEstimator>(StereoOdometryParams{}, calib));
  SerialExecutor ex;
  drivers::StereoFrame f;
  while (true) {
    auto more = (*src)->next(f);
    if (!more || !*more) break;
    SlamFrameResult r;
    EXPECT_TRUE(vo.process(f.left.cview(), f.right.cview(), r, ex).isOk());
    out.push_back(r.T_world_cam);
  }
  return out;
}

double finalError(const std::vector<Eigen::Isometry3d>& gt,
                  const std::vector<Eigen::Isometry3d>& est) {
  return (gt.back().translation() - est.back().translation()).norm();
}

// Root mean square of the position errors over every frame (no alignment).
double rmsError(const std::vector<Eigen::Isometry3d>& gt,
                const std::vector<Eigen::Isometry3d>& est) {
  double s = 0;
  for (std::size_t i = 0; i < gt.size(); ++i)
    s += (gt[i].translation() - est[i].translation()).squaredNorm();
  return std::sqrt(s / static_cast<double>(gt.size()));
}

}  // namespace

// The blimp loop (about 70 m at 25-30 m altitude, 2.2 m baseline), rendered at half size to
// keep the test short; `svslam run` on the full-size flight is measured in docs/slam.md.
TEST(SlamSystem, SyntheticBlimpLoopWithinTargetsAndBetterThanOdometry) {
  const RunOut r = runSlam("synthetic:width=512,height=384", SlamSystemParams{});
  const std::vector<Eigen::Isometry3d> vo = runVo("synthetic:width=512,height=384");
  ASSERT_EQ(r.gt.size(), 100u);
  ASSERT_EQ(r.est.size(), 100u);
  ASSERT_EQ(vo.size(), 100u);
  // Final errors without any alignment (both start at the first camera): the loop's drift.
  const double e_slam = finalError(r.gt, r.est), e_vo = finalError(r.gt, vo);
  const double rms_slam = rmsError(r.gt, r.est), rms_vo = rmsError(r.gt, vo);
  const double att_slam =
      Eigen::AngleAxisd(r.gt.back().linear().transpose() * r.est.back().linear()).angle() * 180 /
      M_PI;
  auto nees = evaluateNees(r.gt, r.est, r.cov);
  ASSERT_TRUE(nees.isOk()) << nees.status().message();
  // Position covariance: its largest trace over the flight and at the end of the loop.
  double trace_max = 0.0;
  for (const Matrix6d& c : r.cov)
    trace_max = std::max(trace_max, c.bottomRightCorner<3, 3>().trace());
  const double trace_end = r.cov.back().bottomRightCorner<3, 3>().trace();
  std::printf(
      "blimp loop 512x384: final position error EKF %.4f m, VO %.4f m; rms over the "
      "frames EKF %.4f m, VO %.4f m; attitude %.3f deg; mean NEES %.2f, position within "
      "2 sigma %.1f %% of frames; max landmarks in state %d, re-perceived %d, anchors restored "
      "%d; position covariance trace max %.3g, at the end %.3g m^2\n",
      e_slam, e_vo, rms_slam, rms_vo, att_slam, nees->mean_nees, nees->position_within_2sigma_pct,
      r.max_in_state, r.reperceived, r.restored, trace_max, trace_end);
  EXPECT_LE(e_slam, 0.15);
  EXPECT_LE(att_slam, 0.5);
  // 3x better than odometry at the end of the loop. Measured on this seed (first-frame anchors
  // brought back on the loop, the odometry's first pair searched widely): final 0.0039 m
  // against 0.0260 m (6.7x), rms over the frames 0.0101 m against 0.0283 m (2.8x); over seeds
  // 1-6 the final-frame ratio ranges 2.4-29 (docs/slam.md).
  EXPECT_LE(e_slam * 3.0, e_vo);
  EXPECT_LE(rms_slam * 2.0, rms_vo);
  // The loop closes on the first frame's landmarks: they come back into the state and the
  // position covariance shrinks visibly from its largest value (measured: 3.3x).
  EXPECT_GT(r.restored, 0);
  EXPECT_LE(trace_end * 2.0, trace_max);
  EXPECT_GE(nees->position_within_2sigma_pct, 90.0);
  EXPECT_GT(r.reperceived, 0);
  EXPECT_LE(r.max_in_state, SlamSystemParams{}.ekf.max_landmarks);
  // Retired landmarks stay in the map with finite estimates.
  int retired = 0;
  for (const MapLandmark& m : r.map) {
    EXPECT_TRUE(m.p_world.allFinite());
    EXPECT_TRUE(m.cov.allFinite());
    retired += m.active ? 0 : 1;
  }
  EXPECT_GT(retired, 0);
}

TEST(SlamSystem, SmallLandmarkCapIsRespected) {
  SlamSystemParams p;
  p.ekf.max_landmarks = 20;
  const RunOut r = runSlam("synthetic:width=320,height=240,frames=30", p);
  ASSERT_EQ(r.est.size(), 30u);
  EXPECT_LE(r.max_in_state, 20);
  EXPECT_GE(r.map.size(), static_cast<std::size_t>(r.max_in_state));  // retired ones stay
  // On this fast loop (30 frames) first-frame landmarks leave the state and come back.
  EXPECT_GT(r.restored, 0);
}

// Three laps of the same closed flight (loop_frames: frame 60 is frame 0 again): the filter keeps
// creating landmarks on the ground it has mapped; a retired one whose voxel already holds a better
// localised one is dropped, so the map holds fewer than were created (here 265 of 285), lists each
// landmark once, sorted by id, with at most one retired landmark per voxel. (The plateau of a long
// flight: scripts/soak.sh, docs/pipeline.md "Soak".)
TEST(SlamSystem, MapKeepsOneRetiredLandmarkPerVoxel) {
  SlamSystemParams p;
  p.ekf.max_landmarks = 40;
  const RunOut r = runSlam("synthetic:width=320,height=240,frames=180,loop_frames=60", p);
  ASSERT_EQ(r.in_map.size(), 180u);
  const int lap1 = r.in_map[59], lap3 = r.in_map[179];
  int max_id = -1;
  for (const MapLandmark& m : r.map) max_id = std::max(max_id, m.id);
  ASSERT_EQ(static_cast<int>(r.map.size()), lap3);
  EXPECT_GT(max_id + 1, 2 * lap1) << "landmarks created over three laps";
  EXPECT_LT(lap3, max_id + 1) << "no retired landmark shared a voxel";
  std::map<std::tuple<long, long, long>, int> per_voxel;
  for (std::size_t i = 0; i < r.map.size(); ++i) {
    if (i > 0) {
      EXPECT_LT(r.map[i - 1].id, r.map[i].id);
    }
    const MapLandmark& m = r.map[i];
    if (m.active || m.anchored) continue;
    const Eigen::Vector3d v = (m.p_world / p.map_voxel_m).array().floor();
    const std::tuple<long, long, long> key{std::lround(v.x()), std::lround(v.y()),
                                           std::lround(v.z())};
    EXPECT_EQ(++per_voxel[key], 1);
  }
}

TEST(SlamSystem, SameInputSameOutput) {
  SlamSystemParams p;
  p.ekf.max_landmarks = 20;  // retirements and restorations (the fast loop above)
  const RunOut a = runSlam("synthetic:width=320,height=240,frames=30", p);
  const RunOut b = runSlam("synthetic:width=320,height=240,frames=30", p);
  ASSERT_EQ(a.est.size(), b.est.size());
  EXPECT_GT(a.restored, 0);
  for (std::size_t i = 0; i < a.est.size(); ++i) {
    EXPECT_TRUE(a.est[i].matrix() == b.est[i].matrix()) << "frame " << i;
    EXPECT_TRUE(a.cov[i] == b.cov[i]) << "frame " << i;
  }
}

// The calibration's uncertainty and the drift (slam/calibration_consider.hpp,
// slam/drift_consider.hpp) are published beside the filter's covariance, from the world origin
// (the first pose), and never enter the filter: the same poses and filter covariances with and
// without them; none for a rendered (exact) calibration.
TEST(SlamSystem, ConsiderUncertaintyIsPublishedBesideTheFilter) {
  SlamSystemParams p;
  p.calibration_uncertainty.sigma_principal_point_px = 1.5;
  p.calibration_uncertainty.sigma_scale = 0.004;
  p.drift_uncertainty.sigma_rotation_rad_per_m = 0.5e-3;
  const std::string spec = "synthetic:width=320,height=240,frames=12";
  const RunOut exact = runSlam(spec, p);
  const RunOut inexact = runSlam(spec, p, 0, /*inexact=*/true);
  ASSERT_EQ(exact.est.size(), 12u);
  ASSERT_EQ(inexact.est.size(), 12u);
  auto src = drivers::openStereoSource(spec);
  ASSERT_TRUE(src.isOk());
  // The calibration's and the drift's covariances (slam/*_consider.hpp) along the trajectory.
  const CalibrationConsider model(p.calibration_uncertainty, (*src)->calibration().f_px);
  DriftConsider drift(p.drift_uncertainty);
  Matrix6d expected_drift;
  for (std::size_t i = 0; i < exact.est.size(); ++i) {
    EXPECT_TRUE(exact.est[i].matrix() == inexact.est[i].matrix()) << "frame " << i;
    EXPECT_TRUE(exact.cov[i] == inexact.cov[i]) << "frame " << i;
    EXPECT_EQ(exact.cov_consider[i].cwiseAbs().maxCoeff(), 0.0) << "frame " << i;
    Matrix6d expected;
    ASSERT_TRUE(model.process(Eigen::Isometry3d::Identity(), inexact.est[i], expected));
    ASSERT_TRUE(drift.process(Eigen::Isometry3d::Identity(), inexact.est[i], expected_drift));
    EXPECT_LT((inexact.cov_consider[i] - expected - expected_drift).cwiseAbs().maxCoeff(), 1e-15);
  }
  EXPECT_GT(expected_drift.trace(), 0.0);  // the last frame's: the drift grew along the path
  // It grows with the path: at the last frame the scale's part alone is (0.004 d)^2.
  const double d = inexact.est.back().translation().norm();
  ASSERT_GT(d, 5.0);
  const Eigen::Matrix3d position = inexact.cov_consider.back().bottomRightCorner<3, 3>();
  EXPECT_GE(position.trace(), 0.004 * 0.004 * d * d * (1 - 1e-9));
  EXPECT_EQ(inexact.cov_consider.front().cwiseAbs().maxCoeff(), 0.0);  // the origin
}

TEST(SlamSystem, KittiNoWorseThanOdometry) {
  const std::string dir = std::string(SVSLAM_DATA_DIR) + "/kitti_odometry_seq_a";
  if (!fs::exists(dir + "/poses.txt")) GTEST_SKIP() << "no KITTI data at " << dir;
  const RunOut r = runSlam("kitti:" + dir, SlamSystemParams{});
  auto gt = drivers::readTrajectory(dir + "/poses.txt");
  ASSERT_TRUE(gt.isOk());
  TrajectoryEvalParams ep;
  ep.segment_lengths_m = {10, 20, 40};
  ep.step_frames = 1;
  auto ms = evaluateTrajectory(gt->poses, r.est, ep);
  auto mv = evaluateTrajectory(gt->poses, r.vo, ep);
  ASSERT_TRUE(ms.isOk() && mv.isOk());
  std::printf("KITTI seq_a drift: EKF %.3f %%, VO %.3f %%\n", ms->t_err_pct, mv->t_err_pct);
  EXPECT_LE(ms->t_err_pct, 1.5);
  EXPECT_LE(ms->t_err_pct, mv->t_err_pct * 1.05);
}

TEST(SlamSystem, EurocNoWorseThanOdometry) {
  const std::string dir = std::string(SVSLAM_DATA_DIR) + "/euroc_mh01_first320";
  const std::string gt_path = dir + "/groundtruth_per_frame_cam0_times.txt";
  if (!fs::exists(gt_path)) GTEST_SKIP() << "no EuRoC data at " << dir;
  const RunOut r = runSlam("euroc:" + dir, SlamSystemParams{});
  auto gt = drivers::readTrajectory(gt_path);
  auto tbs = drivers::eurocBodyToRectifiedLeft(dir);  // the camera svslam tracks
  ASSERT_TRUE(gt.isOk() && tbs.isOk());
  for (auto& T : gt->poses) T = T * *tbs;
  drivers::TrajectoryFile es, vo;
  es.format = vo.format = drivers::TrajectoryFormat::kTum;
  es.t_ns = vo.t_ns = r.t_ns;
  es.poses = r.est;
  vo.poses = r.vo;
  std::vector<Eigen::Isometry3d> g1, e1, g2, e2;
  ASSERT_TRUE(drivers::associateTrajectories(*gt, es, 0.02, g1, e1).isOk());
  ASSERT_TRUE(drivers::associateTrajectories(*gt, vo, 0.02, g2, e2).isOk());
  TrajectoryEvalParams ep;
  ep.segment_lengths_m = {1, 2, 4};
  ep.step_frames = 1;
  auto ms = evaluateTrajectory(g1, e1, ep);
  auto mv = evaluateTrajectory(g2, e2, ep);
  ASSERT_TRUE(ms.isOk() && mv.isOk());
  std::printf("EuRoC MH01/320 ATE: EKF %.4f m, VO %.4f m\n", ms->ate_rmse_m, mv->ate_rmse_m);
  EXPECT_LE(ms->ate_rmse_m, 0.10);
  EXPECT_LE(ms->ate_rmse_m, mv->ate_rmse_m * 1.10);
}

TEST(SlamSystem, BadParamsAndInput) {
  SlamSystemParams p;
  p.candidate_fraction = 0;
  StereoCalibration c{500, 160, 120, 0.5, 320, 240};
  SlamSystem bad(p, StereoOdometryParams{}, c);
  EXPECT_NE(bad.initStatus().message().find("candidate_fraction"), std::string::npos);
  // Camera-loss parameters are named by their configuration keys.
  p = SlamSystemParams{};
  p.bearing_init.r_max_m = 0.1;
  EXPECT_NE(SlamSystem(p, StereoOdometryParams{}, c).initStatus().message().find(
                "slam.bearing_r_max_m"),
            std::string::npos);
  p = SlamSystemParams{};
  p.right_camera.resume_frames = 0;
  EXPECT_NE(SlamSystem(p, StereoOdometryParams{}, c).initStatus().message().find(
                "slam.right_camera_"),
            std::string::npos);
  p = SlamSystemParams{};
  p.mono_candidate_max_frames = 1;
  EXPECT_FALSE(SlamSystem(p, StereoOdometryParams{}, c).initStatus().isOk());
  FrameByFrame ok(StereoOdometryParams{}, c,
                  std::make_unique<SlamSystem>(SlamSystemParams{}, StereoOdometryParams{}, c));
  ASSERT_TRUE(ok.initStatus().isOk());
  ImageU8 small(100, 100);
  SlamFrameResult out;
  SerialExecutor ex;
  EXPECT_FALSE(ok.process(small.cview(), small.cview(), out, ex).isOk());
}

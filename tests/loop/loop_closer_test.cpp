// LoopCloser end to end on a rendered two-lap flight: keyframes with drifting odometry (noise
// drawn from the covariance it declares), a vocabulary trained on another flight; the loops of
// the second lap are found, all true, and the pose graph removes most of the drift. Also the
// front end's keyframe rule and covariance chain, and determinism.
#include "loop/loop_closer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "drivers/synthetic/synthetic_flight.hpp"
#include "loop/relative_pose.hpp"

using namespace svslam;

namespace {

drivers::SyntheticFlightParams flight(std::uint64_t seed, int frames, int loop_frames,
                                      double loop_m) {
  drivers::SyntheticFlightParams p;
  p.width = 320;
  p.height = 240;
  p.frames = frames;
  p.loop_frames = loop_frames;
  p.loop_length_m = loop_m;
  p.seed = seed;
  return p;
}

DenseStereoParams denseParams() {
  DenseStereoParams d;
  d.max_disp = 48;
  return d;
}

// A vocabulary from another flight (seed 99): none of the evaluation frames.
BinaryVocabulary trainVocabulary() {
  drivers::SyntheticFlight f(flight(99, 12, 0, 120));
  OrbExtractor orb(KeyframeParams::defaultOrb(), 320, 240);
  std::vector<std::vector<OrbDescriptor>> d;
  std::vector<OrbKeypoint> kp;
  ImageU8 l, r;
  for (int i = 0; i < 12; ++i) {
    EXPECT_TRUE(f.render(i, l, r).isOk());
    d.emplace_back();
    EXPECT_TRUE(orb.process(l.cview(), kp, d.back()).isOk());
  }
  VocabularyParams vp;
  vp.depth = 3;
  auto v = BinaryVocabulary::train(d, vp);
  EXPECT_TRUE(v.isOk()) << v.status().message();
  return std::move(v).value();
}

struct Outcome {
  std::vector<AcceptedLoop> loops;
  std::vector<Eigen::Isometry3d> corrected, online, truth;
  std::vector<std::int64_t> frames;
  LoopCloserStats stats;
  std::size_t memory_bytes = 0, points = 0;  // the closer's, in all; points of every keyframe
};

// Keyframes every 3rd frame of two 60-frame laps over a 60 m loop; online poses chained from
// noisy relative poses (sigma 2 mrad, 2 cm per keyframe edge).
// wrong_fraction: the test hook re-attaching that share of the verified loops to wrong keyframes.
// reset_frame >= 0: the estimator is reset there (a new world, world_epoch 1, the camera at the
// identity; the edge across it carries no information).
Outcome run(const BinaryVocabulary& voc, double wrong_fraction = 0, int reset_frame = -1) {
  drivers::SyntheticFlight f(flight(3, 120, 60, 60));
  DenseStereo dense(denseParams(), 320, 240);
  LoopCloserParams p;
  p.place.exclude_recent = 8;
  p.wrong_loop_fraction = wrong_fraction;
  p.wrong_loop_seed = 5;
  LoopCloser closer(p, voc);
  EXPECT_TRUE(closer.initStatus().isOk()) << closer.initStatus().message();
  KeyframeBuilder builder(p.keyframe, f.calibration());
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double sr = 2e-3, st = 0.02;
  Matrix6d cov = Matrix6d::Zero();
  cov.diagonal() << sr * sr, sr * sr, sr * sr, st * st, st * st, st * st;
  Outcome o;
  ImageU8 l, r;
  DisparityResult d;
  Eigen::Isometry3d T_online = f.pose(0), T_online_prev = T_online;
  for (int i = 0, id = 0; i < 120; i += 3, ++id) {
    EXPECT_TRUE(f.render(i, l, r).isOk());
    EXPECT_TRUE(dense.process(l.cview(), r.cview(), d).isOk());
    Eigen::Isometry3d Z = Eigen::Isometry3d::Identity();
    if (i > 0) {
      Z = f.pose(i - 3).inverse() * f.pose(i);
      Vector6d e;
      for (int k = 0; k < 6; ++k) e[k] = n01(rng) * (k < 3 ? sr : st);
      Eigen::Isometry3d noisy = Z;
      noisy.linear() = expSO3(e.head<3>()) * Z.linear();
      noisy.translation() += e.tail<3>();
      Z = noisy;
      T_online = T_online * Z;
    }
    Matrix6d edge_cov = cov;
    if (reset_frame >= 0 && i == reset_frame) {  // the online pose jumps to the new world
      Z = T_online_prev.inverse();
      T_online = Eigen::Isometry3d::Identity();
      edge_cov.diagonal() << 100, 100, 100, 1e8, 1e8, 1e8;
    }
    T_online_prev = T_online;
    Keyframe kf;
    if (reset_frame >= 0 && i >= reset_frame) {
      kf.world_epoch = 1;
      kf.world_since_t_ns = f.timeNs(reset_frame);
    }
    kf.id = id;
    kf.frame = i;
    kf.t_ns = f.timeNs(i);
    kf.T_world_cam = T_online;
    EXPECT_TRUE(builder.process(l.cview(), d, kf).isOk());
    o.points += kf.size();
    bool optimised = false;
    const Status s = closer.process(std::move(kf), edge_cov, Z, optimised);
    EXPECT_TRUE(s.isOk()) << s.message();
    o.online.push_back(T_online);
    o.truth.push_back(f.pose(i));
    o.frames.push_back(i);
  }
  bool optimised = false;
  EXPECT_TRUE(closer.finish(optimised).isOk());
  o.loops = closer.acceptedLoops();
  o.corrected = closer.correctedKeyframes();
  o.stats = closer.stats();
  o.memory_bytes = closer.memoryBytes();
  return o;
}

double ate(const std::vector<Eigen::Isometry3d>& est, const std::vector<Eigen::Isometry3d>& gt) {
  double s = 0;
  for (std::size_t k = 0; k < est.size(); ++k)
    s += (est[k].translation() - gt[k].translation()).squaredNorm();
  return std::sqrt(s / static_cast<double>(est.size()));
}

// Every accepted loop of `o` agrees with the true relative pose within its covariance.
void expectTrueLoops(const Outcome& o) {
  for (const AcceptedLoop& a : o.loops) {
    // chi2 6 dof, 99.9 % = 22.46.
    const Eigen::Isometry3d truth = o.truth[static_cast<std::size_t>(a.query)].inverse() *
                                    o.truth[static_cast<std::size_t>(a.candidate)];
    const Vector6d r = relativePoseResidual(Eigen::Isometry3d::Identity(), truth,
                                            a.T_query_candidate);
    const double nees = r.dot(a.covariance.ldlt().solve(r));
    EXPECT_LT(nees, 22.46) << "false loop " << a.query << " -> " << a.candidate << ", error "
                           << r.transpose() << ", " << a.inliers << " inliers";
    EXPECT_FALSE(a.injected);
  }
}

TEST(LoopCloserTest, SecondLapLoopsAreTrueAndRemoveTheDrift) {
  const BinaryVocabulary voc = trainVocabulary();
  const Outcome o = run(voc);
  ASSERT_GE(o.loops.size(), 4u);
  expectTrueLoops(o);
  const double before = ate(o.online, o.truth), after = ate(o.corrected, o.truth);
  std::printf("keyframe ATE online %.3f m, corrected %.3f m, %zu loops\n", before, after,
              o.loops.size());
  EXPECT_LT(after, 0.5 * before);
  // Memory in all (keyframes, inverted index, poses): at most 40 KiB a keyframe, and the same
  // bound for full keyframes of 400 points (the per-point part scaled to 400).
  const double kf = static_cast<double>(o.corrected.size());
  const double per_point = static_cast<double>(o.memory_bytes) / static_cast<double>(o.points);
  std::printf("loop closer memory %zu B for %zu keyframes, %.1f points each: %.0f B a keyframe\n",
              o.memory_bytes, o.corrected.size(), o.points / kf, o.memory_bytes / kf);
  EXPECT_LE(static_cast<double>(o.memory_bytes) / kf, 40.0 * 1024);
  EXPECT_LE(per_point * 400.0, 40.0 * 1024);
  // Deterministic.
  const Outcome again = run(voc);
  ASSERT_EQ(again.corrected.size(), o.corrected.size());
  for (std::size_t k = 0; k < o.corrected.size(); ++k)
    EXPECT_TRUE(again.corrected[k].matrix() == o.corrected[k].matrix());

  // Robustness: a tenth of the verified loops re-attached to wrong keyframes (the test hook;
  // the issue asks for 5 %, more here to inject more than one in 40 keyframes): PCM accepts
  // none of them, and the corrected trajectory's error moves by less than 5 %.
  const Outcome faulty = run(voc, 0.10);
  EXPECT_GE(faulty.stats.injected_wrong, 2);
  EXPECT_EQ(faulty.stats.injected_wrong_accepted, 0);
  expectTrueLoops(faulty);
  const double after_faulty = ate(faulty.corrected, faulty.truth);
  std::printf("with %d wrong loops injected: corrected %.4f m (clean %.4f m)\n",
              faulty.stats.injected_wrong, after_faulty, after);
  EXPECT_LT(std::abs(after_faulty - after), 0.05 * after);
}

// A reset at frame 75 (the second lap): the new world's first keyframe is the gauge (it stays
// where the online estimate put it, the identity) and the loops across the reset bring the first
// lap into the new world: every corrected keyframe near the truth expressed in that world.
TEST(LoopCloserTest, ResetKeepsTheNewWorldAndBringsTheOldOneIntoIt) {
  const BinaryVocabulary voc = trainVocabulary();
  const int reset = 75;
  const Outcome o = run(voc, 0, reset);
  EXPECT_EQ(o.stats.world_resets, 1);
  int across = 0;
  for (const AcceptedLoop& a : o.loops) across += a.query_frame >= reset && a.candidate_frame < reset;
  ASSERT_GE(across, 2);
  drivers::SyntheticFlight f(flight(3, 120, 60, 60));
  const Eigen::Isometry3d W = f.pose(reset).inverse();  // new world <- old world (truth)
  double pre = 0, post = 0, online_pre = 0;
  int n_pre = 0, n_post = 0;
  for (std::size_t k = 0; k < o.corrected.size(); ++k) {
    const Eigen::Isometry3d truth = W * o.truth[k];
    const double e = (o.corrected[k].translation() - truth.translation()).squaredNorm();
    if (o.frames[k] < reset) {
      pre += e;
      online_pre += (o.online[k].translation() - truth.translation()).squaredNorm();
      ++n_pre;
    } else {
      post += e;
      ++n_post;
      if (o.frames[k] == reset) {  // the gauge
        EXPECT_TRUE(o.corrected[k].isApprox(Eigen::Isometry3d::Identity(), 1e-12));
      }
    }
  }
  pre = std::sqrt(pre / n_pre);
  post = std::sqrt(post / n_post);
  online_pre = std::sqrt(online_pre / n_pre);
  std::printf("reset: keyframes in the new world, rms before the reset %.3f m (online %.1f m), "
              "after %.3f m\n", pre, online_pre, post);
  EXPECT_GT(online_pre, 10.0);
  EXPECT_LT(pre, 0.5);
  EXPECT_LT(post, 0.5);
}

TEST(LoopCloserTest, FrontEndChainsMotionCovariances) {
  drivers::SyntheticFlight f(flight(3, 30, 0, 60));
  LoopCloserParams p;
  LoopFrontEnd fe(p, f.calibration());
  ASSERT_TRUE(fe.initStatus().isOk());
  DenseStereo dense(denseParams(), 320, 240);
  ImageU8 l, r;
  DisparityResult d;
  Matrix6d C_m = Matrix6d::Zero();
  C_m.diagonal() << 1e-8, 1e-8, 1e-8, 1e-6, 1e-6, 1e-6;
  int made_count = 0;
  Matrix6d last_cov = Matrix6d::Zero();
  Eigen::Isometry3d last_T = Eigen::Isometry3d::Identity();
  std::int64_t prev_kf_frame = 0, last_kf_frame = 0;
  for (int i = 0; i < 12; ++i) {
    ASSERT_TRUE(f.render(i, l, r).isOk());
    ASSERT_TRUE(dense.process(l.cview(), r.cview(), d).isOk());
    LoopFrameInput in;
    in.frame = i;
    in.t_ns = f.timeNs(i);
    in.T_world_cam = f.pose(i);
    in.motion_valid = i > 0;
    if (i > 0) in.T_cur_prev = f.pose(i).inverse() * f.pose(i - 1);
    in.motion_cov = C_m;
    in.left = l.cview();
    in.dense = &d;
    bool made = false;
    Keyframe kf;
    Matrix6d cov;
    Eigen::Isometry3d T;
    ASSERT_TRUE(fe.process(in, made, kf, cov, T).isOk());
    if (made) {
      prev_kf_frame = last_kf_frame;
      last_kf_frame = kf.frame;
    }
    if (made && made_count++ > 0) {
      last_cov = cov;
      last_T = T;
    }
  }
  ASSERT_GE(made_count, 2);  // 60 m loop, 0.5 m a frame, ~2.7 m between keyframes
  EXPECT_TRUE(isValidCovariance(last_cov));
  // The chained motions give the true relative pose of the last two keyframes.
  const Eigen::Isometry3d truth = f.pose(static_cast<int>(prev_kf_frame)).inverse() *
                                  f.pose(static_cast<int>(last_kf_frame));
  EXPECT_LT((truth.inverse() * last_T).translation().norm(), 1e-9);
  // Translation variance grows with the number of chained frames (>= 5 of 1e-6 each).
  const double var_t = last_cov.bottomRightCorner<3, 3>().trace();
  EXPECT_GT(var_t, 3 * 4e-6);
}

}  // namespace

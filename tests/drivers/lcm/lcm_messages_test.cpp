// LCM message conversions: round trips through the wire bytes, and rejection of every
// malformed case (non-finite or asymmetric pose/covariance, wrong sizes, unknown commands,
// truncated and garbage bytes).
#include "drivers/lcm/lcm_messages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace svslam::drivers {
namespace {

template <class Msg>
Msg roundTripBytes(const Msg& m) {
  std::vector<std::uint8_t> buf;
  EXPECT_TRUE(encodeLcm(m, buf).isOk());
  Msg back;
  Status s = decodeLcm(buf.data(), buf.size(), back);
  EXPECT_TRUE(s.isOk()) << s.message();
  return back;
}

PoseReport samplePose() {
  PoseReport r;
  r.t_ns = 1'700'000'000'123'456'000;
  r.publish_t_ns = r.t_ns + 7'000'000;
  r.seq = 42;
  r.T_world_cam.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  r.T_world_cam.translation() = Eigen::Vector3d(1.5, -2.25, 10.0);
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random();
  r.cov = A * A.transpose() * 1e-3;
  r.status = TrackingStatus::kLost;
  r.motion_inliers = 87;
  r.motion_residual_per_dof = 0.55;
  r.observation_nis_per_dof = 0.75;
  r.landmarks_observed = 23;
  r.search = SearchKind::kRepredicted;
  return r;
}

TEST(LcmMessages, PoseRoundTripKeepsPoseCovarianceAndTimes) {
  const PoseReport r = samplePose();
  auto m = toLcm(r);
  ASSERT_TRUE(m.isOk()) << m.status().message();
  EXPECT_EQ(m->utime, 1'700'000'000'123'456);
  EXPECT_EQ(m->publish_utime - m->utime, 7000);
  EXPECT_EQ(m->status, svslam_lcm::pose_t::LOST);
  EXPECT_DOUBLE_EQ(m->covariance[1 * 6 + 4], r.cov(1, 4));  // row-major
  auto back = fromLcm(roundTripBytes(*m));
  ASSERT_TRUE(back.isOk()) << back.status().message();
  EXPECT_EQ(back->t_ns, r.t_ns);
  EXPECT_EQ(back->publish_t_ns, r.publish_t_ns);
  EXPECT_EQ(back->seq, 42);
  EXPECT_EQ(back->frame_id, "svslam_world");
  EXPECT_EQ(back->status, TrackingStatus::kLost);
  EXPECT_TRUE(back->T_world_cam.isApprox(r.T_world_cam, 1e-12));
  EXPECT_EQ(back->cov, r.cov);
  EXPECT_EQ(m->search, svslam_lcm::pose_t::REPREDICTED);
  EXPECT_EQ(back->motion_inliers, 87);
  EXPECT_EQ(back->motion_residual_per_dof, 0.55);
  EXPECT_EQ(back->observation_nis_per_dof, 0.75);
  EXPECT_EQ(back->landmarks_observed, 23);
  EXPECT_EQ(back->search, SearchKind::kRepredicted);
}

TEST(LcmMessages, PoseRejectsNaNAsymmetryAndBadRotation) {
  PoseReport r = samplePose();
  r.T_world_cam.translation().x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(toLcm(r).isOk());
  r = samplePose();
  r.cov(2, 2) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(toLcm(r).isOk());
  r = samplePose();
  r.cov(0, 5) += 1e-3;  // no longer symmetric
  auto bad = toLcm(r);
  ASSERT_FALSE(bad.isOk());
  EXPECT_NE(bad.status().message().find("symmetric"), std::string::npos);
  r = samplePose();
  r.cov(3, 3) = -1.0;
  EXPECT_FALSE(toLcm(r).isOk());
  r = samplePose();
  r.T_world_cam.linear() *= 1.1;  // not a rotation
  EXPECT_FALSE(toLcm(r).isOk());
  r = samplePose();
  r.frame_id.clear();
  EXPECT_FALSE(toLcm(r).isOk());

  auto m = toLcm(samplePose()).value();
  auto m2 = m;
  m2.covariance[7] = std::nan("");
  EXPECT_FALSE(fromLcm(m2).isOk());
  m2 = m;
  m2.orientation[0] = 3.0;  // not unit
  EXPECT_FALSE(fromLcm(m2).isOk());
  m2 = m;
  m2.status = 7;
  EXPECT_FALSE(fromLcm(m2).isOk());
  m2 = m;
  m2.status = svslam_lcm::pose_t::MONOCULAR;  // the right camera lost: a valid status
  ASSERT_TRUE(fromLcm(m2).isOk());
  EXPECT_EQ(fromLcm(m2)->status, TrackingStatus::kMonocular);
  m2 = m;
  m2.utime = std::numeric_limits<std::int64_t>::max();  // ns overflow
  EXPECT_FALSE(fromLcm(m2).isOk());
  m2 = m;
  m2.frame_id.clear();  // what toLcm refuses to send is refused on receipt (found by fuzzing)
  auto no_frame_check = m2;
  m2 = m;
  m2.search = 3;
  EXPECT_FALSE(fromLcm(m2).isOk());
  m2 = m;
  m2.motion_inliers = -1;
  EXPECT_FALSE(fromLcm(m2).isOk());
  m2 = m;
  m2.observation_nis_per_dof = std::nan("");
  EXPECT_FALSE(fromLcm(m2).isOk());
  r = samplePose();
  r.motion_residual_per_dof = -0.5;
  EXPECT_FALSE(toLcm(r).isOk());
  m2 = no_frame_check;
  auto no_frame = fromLcm(m2);
  ASSERT_FALSE(no_frame.isOk());
  EXPECT_NE(no_frame.status().message().find("frame_id"), std::string::npos);
}

TEST(LcmMessages, StatsRoundTripAndRejection) {
  StatsReport r;
  r.t_ns = 5'000'000'000;
  r.frames_in = 100;
  r.frames_out = 97;
  r.frames_dropped = 3;
  r.frames_tracked = 90;
  r.stages = {{"stereo", 4.5, 9.25, 12.0}, {"slam", 7.0, 15.5, 30.0}};
  r.queues = {{"capture->stereo", 1, 2, 3}, {"stereo->slam", 0, 2, 0}};
  r.e2e_p50_ms = 20.0;
  r.e2e_p99_ms = 40.0;
  r.e2e_max_ms = 55.5;
  r.stalled_stage = "estimator";
  r.stalled_ms = 1250.5;
  r.stalls = {{"mapper", 2, 3000.25}, {"estimator", 1, 1250.5}};
  auto m = toLcm(r);
  ASSERT_TRUE(m.isOk()) << m.status().message();
  auto back = fromLcm(roundTripBytes(*m));
  ASSERT_TRUE(back.isOk()) << back.status().message();
  EXPECT_EQ(back->t_ns, r.t_ns);
  EXPECT_EQ(back->frames_dropped, 3);
  ASSERT_EQ(back->stages.size(), 2u);
  EXPECT_EQ(back->stages[1].name, "slam");
  EXPECT_EQ(back->stages[1].p99_ms, 15.5);
  ASSERT_EQ(back->queues.size(), 2u);
  EXPECT_EQ(back->queues[0].name, "capture->stereo");
  EXPECT_EQ(back->queues[0].drops, 3);
  EXPECT_EQ(back->e2e_max_ms, 55.5);
  EXPECT_EQ(back->stalled_stage, "estimator");
  EXPECT_EQ(back->stalled_ms, 1250.5);
  ASSERT_EQ(back->stalls.size(), 2u);
  EXPECT_EQ(back->stalls[0].stage, "mapper");
  EXPECT_EQ(back->stalls[0].count, 2);
  EXPECT_EQ(back->stalls[0].longest_ms, 3000.25);
  EXPECT_EQ(back->stalls[1].stage, "estimator");

  StatsReport bad = r;
  bad.stalled_ms = 0;  // a stalled stage without its duration
  EXPECT_FALSE(toLcm(bad).isOk());
  bad = r;
  bad.stalls[1].count = 0;
  EXPECT_FALSE(toLcm(bad).isOk());
  bad = r;
  bad.stalls[0].longest_ms = NAN;
  EXPECT_FALSE(toLcm(bad).isOk());
  bad = r;
  bad.stages[0].p99_ms = NAN;
  EXPECT_FALSE(toLcm(bad).isOk());
  bad = r;
  bad.queues[1].depth = -1;
  EXPECT_FALSE(toLcm(bad).isOk());
  auto inconsistent = *m;
  inconsistent.num_stages = 3;  // arrays hold 2
  EXPECT_FALSE(fromLcm(inconsistent).isOk());
  inconsistent = *m;
  inconsistent.num_stalls = 1;  // arrays hold 2
  EXPECT_FALSE(fromLcm(inconsistent).isOk());
  // A stall count that says more strings follow than the bytes hold: refused before decoding.
  std::vector<std::uint8_t> buf;
  ASSERT_TRUE(encodeLcm(*m, buf).isOk());
  svslam_lcm::stats_t out;
  ASSERT_TRUE(decodeLcm(buf.data(), buf.size(), out).isOk());
  EXPECT_FALSE(decodeLcm(buf.data(), buf.size() - 1, out).isOk());
}

TEST(LcmMessages, MapSummaryRoundTripAndRejection) {
  MapSummaryReport r;
  r.t_ns = 1'000'000;
  r.landmarks_in_state = 25;
  r.landmarks_in_map = 300;
  r.points_world = {{1.f, 2.f, 3.f}, {-4.5f, 0.25f, 100.f}};
  auto m = toLcm(r);
  ASSERT_TRUE(m.isOk());
  auto back = fromLcm(roundTripBytes(*m));
  ASSERT_TRUE(back.isOk()) << back.status().message();
  EXPECT_EQ(back->landmarks_in_map, 300);
  ASSERT_EQ(back->points_world.size(), 2u);
  EXPECT_EQ(back->points_world[1], Eigen::Vector3f(-4.5f, 0.25f, 100.f));
  r.points_world[0].y() = NAN;
  EXPECT_FALSE(toLcm(r).isOk());
}

TEST(LcmMessages, CommandsParseAndUnknownIsNamed) {
  for (auto k : {CommandKind::kReset, CommandKind::kSaveMap, CommandKind::kPause,
                 CommandKind::kResume, CommandKind::kShutdown}) {
    Command c;
    c.t_ns = 3'000;
    c.seq = 9;
    c.kind = k;
    c.argument = k == CommandKind::kSaveMap ? "/tmp/map.bin" : "";
    c.token = "shared-token-42";
    auto m = toLcm(c);
    ASSERT_TRUE(m.isOk());
    auto back = fromLcm(roundTripBytes(*m));
    ASSERT_TRUE(back.isOk()) << back.status().message();
    EXPECT_EQ(back->kind, k);
    EXPECT_EQ(back->seq, 9);
    EXPECT_EQ(back->argument, c.argument);
    EXPECT_EQ(back->token, c.token);
  }
  svslam_lcm::command_t m;
  m.utime = 0;
  m.seq = 1;
  m.command = "explode";
  auto bad = fromLcm(m);
  ASSERT_FALSE(bad.isOk());
  EXPECT_NE(bad.status().message().find("'explode'"), std::string::npos);

  CommandStatus st{2'000, 9, "save_map", false, "disk full"};
  auto sm = toLcm(st);
  ASSERT_TRUE(sm.isOk());
  auto sback = fromLcm(roundTripBytes(*sm));
  ASSERT_TRUE(sback.isOk());
  EXPECT_FALSE(sback->ok);
  EXPECT_EQ(sback->message, "disk full");
}

svslam_lcm::stereo_image_t sampleImage(int w, int h, int stride) {
  svslam_lcm::stereo_image_t m;
  m.utime = 123;
  m.seq = 4;
  m.width = w;
  m.height = h;
  m.stride = stride;
  m.f_px = 400.0;
  m.cx_px = w / 2.0;
  m.cy_px = h / 2.0;
  m.baseline_m = 0.12;
  m.left_size = m.right_size = stride * h;
  m.left.resize(std::size_t(m.left_size));
  m.right.resize(std::size_t(m.right_size));
  for (int i = 0; i < m.left_size; ++i) {
    m.left[std::size_t(i)] = std::uint8_t(i * 7);
    m.right[std::size_t(i)] = std::uint8_t(i * 13 + 1);
  }
  return m;
}

TEST(LcmMessages, StereoImageWithPaddedStrideBecomesFrame) {
  const auto m = roundTripBytes(sampleImage(37, 21, 40));
  ASSERT_TRUE(validateStereoImage(m).isOk());
  auto c = calibrationOf(m);
  ASSERT_TRUE(c.isOk());
  EXPECT_EQ(c->width, 37);
  EXPECT_EQ(c->baseline_m, 0.12);
  StereoFrame f;
  ASSERT_TRUE(toStereoFrame(m, f).isOk());
  EXPECT_EQ(f.t_ns, 123'000);
  for (int y = 0; y < 21; ++y)
    for (int x = 0; x < 37; ++x) {
      ASSERT_EQ(f.left(x, y), m.left[std::size_t(y * 40 + x)]);
      ASSERT_EQ(f.right(x, y), m.right[std::size_t(y * 40 + x)]);
    }
  // And back: packed with stride = width.
  auto again = toLcmStereoImage(f.left, f.right, *c, f.t_ns, 4);
  ASSERT_TRUE(again.isOk()) << again.status().message();
  EXPECT_EQ(again->stride, 37);
  EXPECT_EQ(again->left[std::size_t(5 * 37 + 3)], m.left[std::size_t(5 * 40 + 3)]);
}

TEST(LcmMessages, StereoImageRejectsEachInconsistency) {
  auto expectBad = [](svslam_lcm::stereo_image_t m, const char* why) {
    EXPECT_FALSE(validateStereoImage(m).isOk()) << why;
  };
  auto m = sampleImage(16, 8, 16);
  ASSERT_TRUE(validateStereoImage(m).isOk());
  auto b = m;
  b.stride = 15;
  expectBad(b, "stride < width");
  b = m;
  b.left_size -= 1;
  expectBad(b, "left_size");
  b = m;
  b.right.pop_back();
  expectBad(b, "right bytes");
  b = m;
  b.width = 0;
  expectBad(b, "zero width");
  b = m;
  b.f_px = NAN;
  expectBad(b, "NaN focal");
  b = m;
  b.baseline_m = -0.1;
  expectBad(b, "negative baseline");
  b = m;
  b.cx_px = 16.0;
  expectBad(b, "cx outside");
  b = m;
  b.cy_px = -1.0;
  expectBad(b, "cy outside");
}

TEST(LcmMessages, StatsCarryTheCommandCounts) {
  StatsReport r;
  r.commands.accepted = 3;
  for (int k = 0; k < kNumCommandRefusals; ++k) r.commands.refused[k] = 10 + k;
  auto m = toLcm(r);
  ASSERT_TRUE(m.isOk()) << m.status().message();
  EXPECT_EQ(m->commands_refused_bad_token, 12);
  auto back = fromLcm(roundTripBytes(*m));
  ASSERT_TRUE(back.isOk()) << back.status().message();
  EXPECT_EQ(back->commands.accepted, 3);
  EXPECT_EQ(back->commands.refused, r.commands.refused);
  r.commands.refused[1] = -1;
  EXPECT_FALSE(toLcm(r).isOk());
}

TEST(LcmMessages, TruncatedGarbageAndLyingCountsAreRejectedWithoutThrowing) {
  auto cmd = toLcm(Command{1, 2, CommandKind::kPause, "x", ""}).value();
  std::vector<std::uint8_t> buf;
  ASSERT_TRUE(encodeLcm(cmd, buf).isOk());
  svslam_lcm::command_t out;
  for (std::size_t n = 0; n < buf.size(); ++n)
    EXPECT_FALSE(decodeLcm(buf.data(), n, out).isOk()) << "truncated at " << n;
  // A string length of 0 or a huge one behind a valid hash.
  auto lie = buf;
  lie[8 + 16 + 3] = 0;  // low byte of the command's length (big-endian)
  EXPECT_FALSE(decodeLcm(lie.data(), lie.size(), out).isOk());
  lie = buf;
  lie[8 + 16] = 0x7f;
  EXPECT_FALSE(decodeLcm(lie.data(), lie.size(), out).isOk());
  // An image whose left_size claims 2 GB.
  auto img = sampleImage(4, 4, 4);
  ASSERT_TRUE(encodeLcm(img, buf).isOk());
  buf[8 + 60] = 0x7f;
  svslam_lcm::stereo_image_t iout;
  EXPECT_FALSE(decodeLcm(buf.data(), buf.size(), iout).isOk());
  // A map with a negative point count.
  auto map = toLcm(MapSummaryReport{}).value();
  ASSERT_TRUE(encodeLcm(map, buf).isOk());
  buf[8 + 16] = 0xff;
  svslam_lcm::map_summary_t mout;
  EXPECT_FALSE(decodeLcm(buf.data(), buf.size(), mout).isOk());
  // Random bytes, with and without a valid hash in front.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<std::uint8_t> g(rng() % 200);
    for (auto& v : g) v = std::uint8_t(rng());
    if (trial % 2 == 0 && g.size() >= 8) {
      const std::int64_t h = svslam_lcm::stats_t::getHash();
      __int64_t_encode_array(g.data(), 0, 8, &h, 1);
    }
    svslam_lcm::stats_t sout;
    (void)decodeLcm(g.data(), g.size(), sout);  // must not throw or crash
    EXPECT_FALSE(decodeLcm(g.data(), g.size(), out).isOk());
  }
}

}  // namespace
}  // namespace svslam::drivers

// svslam listen: one JSON line per svslam_lcm message, recognised by its type hash, whatever
// the channel; --channel (regex), --types, --count / --count-type; bad options exit 1 naming
// the problem. The messages are written to a file:// log and replayed (no network needed).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "../core/test_files.hpp"
#include "cli_helpers.hpp"
#include "drivers/lcm/lcm_map_tile.hpp"
#include "drivers/lcm/lcm_pose_correction.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "pipeline/cli/listen_lines.hpp"

namespace svslam::cli {
namespace {

namespace fs = std::filesystem;
using drivers::LcmLink;
using drivers::LcmParams;

int countOf(const std::string& s, const std::string& needle) {
  int n = 0;
  for (std::size_t p = s.find(needle); p != std::string::npos; p = s.find(needle, p + 1)) ++n;
  return n;
}

std::vector<std::uint8_t> mapTileBytes() {
  map::DemRaster t;
  t.cell_m = 0.5;
  t.i0 = 4;
  t.j0 = -4;
  t.resize(4, 4);
  for (std::size_t k = 0; k < 8; ++k) {
    t.height_m[k] = 2.0f;
    t.sigma_m[k] = 0.1f;
    t.count[k] = 3.0f;
  }
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(drivers::encodeMapTile(t, 1, -1, 7'000'000'000, 3, bytes).isOk());
  return bytes;
}

std::vector<std::uint8_t> correctionBytes() {
  drivers::PoseCorrectionMessage m;
  m.t_ns = 9'000'000'000;
  m.correction_seq = 2;
  m.loops_accepted = 1;
  m.keyframes_total = 5;
  m.keyframe_t_ns = {1'000'000'000, 2'000'000'000};
  Eigen::Isometry3d c = Eigen::Isometry3d::Identity();
  c.translation() = Eigen::Vector3d(0.5, -0.25, 0.0);
  m.correction = {Eigen::Isometry3d::Identity(), c};
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(drivers::encodePoseCorrection(m, bytes).isOk());
  return bytes;
}

// A log with one message of every svslam type (the image on a channel of the user's choice) and
// one message of another type.
void writeLog(const std::string& path) {
  LcmParams p;
  p.url = "file://" + path + "?mode=w";
  auto link = LcmLink::open(p);
  ASSERT_TRUE(link.isOk()) << link.status().message();
  LcmLink& l = **link;
  drivers::PoseReport pose;
  pose.t_ns = 1'000'000'000;
  pose.publish_t_ns = pose.t_ns + 5'000'000;
  pose.T_world_cam.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  for (int k = 0; k < 6; ++k) pose.cov(k, k) = 1e-4;
  pose.motion_inliers = 76;
  pose.motion_residual_per_dof = 0.5;
  pose.landmarks_observed = 6;
  pose.search = drivers::SearchKind::kRetried;
  ASSERT_TRUE(l.publishPose(pose).isOk());
  drivers::StatsReport stats;
  stats.t_ns = 2'000'000'000;
  stats.frames_in = 10;
  stats.stalled_stage = "mapper";
  stats.stalled_ms = 1500.25;
  stats.stalls = {{"mapper", 2, 2500.5}};
  ASSERT_TRUE(l.publishStats(stats).isOk());
  drivers::MapSummaryReport map;
  map.t_ns = 3'000'000'000;
  map.landmarks_in_state = 2;
  map.landmarks_in_map = 7;
  map.points_world = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(4, 5, 6)};
  ASSERT_TRUE(l.publishMap(map).isOk());
  const auto tile = mapTileBytes();
  ASSERT_TRUE(l.publishRaw(p.map_tile_channel, tile.data(), tile.size()).isOk());
  const auto corr = correctionBytes();
  ASSERT_TRUE(l.publishRaw(p.correction_channel, corr.data(), corr.size()).isOk());
  drivers::Command cmd;
  cmd.t_ns = 4'000'000'000;
  cmd.seq = 11;
  cmd.kind = drivers::CommandKind::kSaveMap;
  cmd.argument = "map.tif";
  cmd.token = "secret-token";
  ASSERT_TRUE(l.publishCommand(cmd).isOk());
  drivers::CommandStatus st;
  st.t_ns = 4'500'000'000;
  st.seq = 11;
  st.command = "save_map";
  st.ok = false;
  st.message = "disabled";
  ASSERT_TRUE(l.publishCommandStatus(st).isOk());
  StereoCalibration c;
  c.f_px = 300.0;
  c.cx_px = 8.0;
  c.cy_px = 6.0;
  c.baseline_m = 0.1;
  c.width = 16;
  c.height = 12;
  ImageU8 left(16, 12), right(16, 12);
  left.fill(40);
  right.fill(60);
  auto img = drivers::toLcmStereoImage(left, right, c, 5'000'000'000, 4);
  ASSERT_TRUE(img.isOk());
  ASSERT_TRUE(l.publishStereoImage("CAM_FRONT", *img).isOk());
  const std::uint8_t other[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  ASSERT_TRUE(l.publishRaw("OTHER", other, sizeof other).isOk());
}

class ListenTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::freshTestDir("svslam_listen_test");
    log_ = (dir_ / "all.lcmlog").string();
    writeLog(log_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  int listen(const std::string& options) {
    const int rc = test::runSvslam("listen --url 'file://" + log_ + "?speed=0' " + options,
                                   dir_ / "out.txt", dir_ / "err.txt");
    out_ = test::slurp(dir_ / "out.txt");
    err_ = test::slurp(dir_ / "err.txt");
    return rc;
  }
  fs::path dir_;
  std::string log_, out_, err_;
};

TEST_F(ListenTest, PrintsEveryTypeOnceWithItsChannel) {
  ASSERT_EQ(listen("--timeout-s 20"), 0) << err_;
  EXPECT_EQ(countOf(out_, "\n"), 8) << out_;
  const char* expected[] = {R"({"type": "pose", "channel": "SVSLAM_POSE")",
                            R"({"type": "stats", "channel": "SVSLAM_STATS")",
                            R"({"type": "map_summary", "channel": "SVSLAM_MAP")",
                            R"({"type": "map_tile", "channel": "SVSLAM_MAP_TILE")",
                            R"({"type": "pose_correction", "channel": "SVSLAM_POSE_CORRECTION")",
                            R"({"type": "command", "channel": "SVSLAM_COMMAND")",
                            R"({"type": "command_status", "channel": "SVSLAM_COMMAND_STATUS")",
                            R"({"type": "stereo_image", "channel": "CAM_FRONT")"};
  for (const char* e : expected) EXPECT_EQ(countOf(out_, e), 1) << e << "\n" << out_;
  EXPECT_NE(out_.find(R"("position": [1, 2, 3])"), std::string::npos) << out_;
  EXPECT_NE(out_.find(R"("motion_inliers": 76, "motion_residual_per_dof": 0.500, )"
                      R"("observation_nis_per_dof": 0.000, "landmarks_observed": 6, )"
                      R"("search": "retried"})"),
            std::string::npos)
      << out_;
  EXPECT_NE(out_.find(R"("landmarks_in_map": 7, "num_points": 2)"), std::string::npos) << out_;
  EXPECT_NE(out_.find(R"("stalled_stage": "mapper", "stalled_ms": 1500.2, )"
                      R"("stalls": [{"stage": "mapper", "count": 2, "longest_ms": 2500.5}])"),
            std::string::npos)
      << out_;
  EXPECT_NE(out_.find(R"("valid_cells": 8, "mean_height_m": 2.0000)"), std::string::npos) << out_;
  EXPECT_NE(out_.find(R"("keyframe_utime": [1000000, 2000000])"), std::string::npos) << out_;
  EXPECT_NE(out_.find(R"("position": [[0, 0, 0], [0.5, -0.25, 0]])"), std::string::npos) << out_;
  EXPECT_NE(out_.find(R"("argument": "map.tif", "has_token": true)"), std::string::npos) << out_;
  EXPECT_EQ(out_.find("secret-token"), std::string::npos) << "the token must never be printed";
  EXPECT_NE(out_.find(R"("ok": false, "message": "disabled")"), std::string::npos) << out_;
  EXPECT_NE(out_.find(R"("left_mean": 40.00, "right_mean": 60.00)"), std::string::npos) << out_;
  EXPECT_EQ(err_, "");
}

TEST_F(ListenTest, ChannelRegexTypesAndCount) {
  ASSERT_EQ(listen("--channel 'SVSLAM_COMMAND.*'"), 0) << err_;
  EXPECT_EQ(countOf(out_, "\n"), 2) << out_;
  EXPECT_EQ(countOf(out_, R"("type": "command")"), 1) << out_;
  EXPECT_EQ(countOf(out_, R"("type": "command_status")"), 1) << out_;

  ASSERT_EQ(listen("--channel SVSLAM_MAP"), 0) << err_;  // a name matches that channel only
  EXPECT_EQ(countOf(out_, "\n"), 1) << out_;
  EXPECT_EQ(countOf(out_, R"("type": "map_summary")"), 1) << out_;

  ASSERT_EQ(listen("--types pose_correction,stereo_image --count 1 --count-type stereo_image"), 0)
      << err_;
  EXPECT_EQ(countOf(out_, "\n"), 2) << out_;

  ASSERT_EQ(listen("--no-stats --no-map-tiles"), 0) << err_;
  EXPECT_EQ(countOf(out_, "\n"), 6) << out_;

  EXPECT_EQ(listen("--count 2"), 1);  // one pose in the log
  EXPECT_NE(err_.find("ended after 1 of the 2 poses"), std::string::npos) << err_;
}

TEST_F(ListenTest, BadOptionsExitOneNamingTheProblem) {
  EXPECT_EQ(listen("--types pose,images"), 1);
  EXPECT_NE(err_.find("unknown message type 'images'"), std::string::npos) << err_;
  EXPECT_EQ(listen("--count-type pose,stats"), 1);
  EXPECT_NE(err_.find("--count-type names one message type"), std::string::npos) << err_;
  EXPECT_EQ(listen("--channel 'SVSLAM_(POSE'"), 1);
  EXPECT_NE(err_.find("is not a regular expression"), std::string::npos) << err_;

  // Nothing on the bus: exit 1 after --timeout-s, naming the channels and the URL.
  EXPECT_EQ(test::runSvslam("listen --url memq:// --channel 'SVSLAM_.*' --timeout-s 0.3 --count 2",
                            dir_ / "out.txt", dir_ / "err.txt"),
            1);
  EXPECT_NE(test::slurp(dir_ / "err.txt")
                .find("nothing on 'SVSLAM_.*' via 'memq://' for 0.3 s (0 of 2 poses received"),
            std::string::npos)
      << test::slurp(dir_ / "err.txt");
}

TEST(ListenLines, UnknownAndMalformedMessages) {
  const std::uint8_t other[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  EXPECT_EQ(listenTypeOf(other, sizeof other), ListenType::kUnknown);
  EXPECT_EQ(listenTypeOf(other, 4), ListenType::kUnknown);
  ListenLine l = listenLine("X", other, sizeof other);
  EXPECT_EQ(l.type, ListenType::kUnknown);
  EXPECT_TRUE(l.json.empty());

  // A map tile cut short: recognised by its hash, refused by the decoder.
  auto tile = mapTileBytes();
  tile.resize(tile.size() - 3);
  EXPECT_EQ(listenTypeOf(tile.data(), tile.size()), ListenType::kMapTile);
  l = listenLine("SVSLAM_MAP_TILE", tile.data(), tile.size());
  EXPECT_EQ(l.type, ListenType::kMapTile);
  EXPECT_TRUE(l.json.empty());
  EXPECT_FALSE(l.error.empty());
}

}  // namespace
}  // namespace svslam::cli

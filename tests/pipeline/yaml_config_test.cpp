// Strict YAML configuration: defaults, overrides, and an error naming the key for every kind of
// bad entry (unknown key, wrong type, out of range, not YAML).
#include "pipeline/config/yaml_config.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "pipeline/config/run_config.hpp"

using svslam::config::ConfigReader;
using svslam::config::parseRunConfig;
using svslam::config::RunConfig;

namespace {

std::string errorOf(const std::string& yaml) {
  RunConfig c;
  const svslam::Status s = parseRunConfig(yaml, "test.yaml", c);
  return s ? "" : s.message();
}

}  // namespace

TEST(RunConfig, EmptyGivesDefaults) {
  RunConfig c;
  ASSERT_TRUE(parseRunConfig("", "empty.yaml", c).isOk());
  RunConfig d;
  EXPECT_EQ(c.source, d.source);
  EXPECT_EQ(c.odometry.stereo_match.max_disp_px, d.odometry.stereo_match.max_disp_px);
  EXPECT_EQ(c.odometry.temporal_match.search_radius_px, d.odometry.temporal_match.search_radius_px);
}

TEST(RunConfig, ValuesAreApplied) {
  RunConfig c;
  ASSERT_TRUE(parseRunConfig("seed: 42\nthreads: 2\nsource: kitti:/x\n"
                             "stereo_match: {max_disp_px: 96, min_zncc: 0.7}\n"
                             "detector: {response: shi-tomasi}\nmotion: {ransac: true}\n"
                             "dense_stereo: {enabled: true, max_disp_px: 96}\n",
                             "t.yaml", c)
                  .isOk());
  EXPECT_EQ(c.seed, 42u);
  EXPECT_EQ(c.odometry.motion.seed, 42u);  // randomness seeded from the config
  EXPECT_EQ(c.threads, 2);
  EXPECT_EQ(c.odometry.dense_stereo.num_stripes, 2);
  EXPECT_EQ(c.source, "kitti:/x");
  EXPECT_EQ(c.odometry.stereo_match.max_disp_px, 96);
  EXPECT_FLOAT_EQ(c.odometry.stereo_match.min_zncc, 0.7f);
  EXPECT_EQ(c.odometry.stereo_match.sigma_mode, svslam::StereoSigmaMode::kFixed);  // default
  RunConfig f;
  ASSERT_TRUE(
      parseRunConfig("stereo_match: {sigma_mode: curvature, sigma_d_px: 0.4}\n", "f.yaml", f)
          .isOk());
  EXPECT_EQ(f.odometry.stereo_match.sigma_mode, svslam::StereoSigmaMode::kCurvature);
  EXPECT_FLOAT_EQ(f.odometry.stereo_match.sigma_d_px, 0.4f);
  EXPECT_EQ(c.odometry.corners.response, svslam::CornerResponse::kShiTomasi);
  EXPECT_TRUE(c.odometry.motion.ransac);
  EXPECT_TRUE(c.odometry.dense);
  EXPECT_EQ(c.odometry.dense_stereo.max_disp, 96);
}

TEST(RunConfig, UnknownKeysAreNamed) {
  EXPECT_NE(errorOf("sead: 3\n").find("'sead'"), std::string::npos);
  EXPECT_NE(errorOf("stereo_match: {max_disparity: 3}\n").find("'stereo_match.max_disparity'"),
            std::string::npos);
  EXPECT_NE(errorOf("detector: {grid: {cols: 3}}\n").find("'detector.grid.cols'"),
            std::string::npos);
}

TEST(RunConfig, DuplicateKeysAreNamed) {
  EXPECT_NE(errorOf("seed: 1\nseed: 2\n").find("duplicate key 'seed'"), std::string::npos)
      << errorOf("seed: 1\nseed: 2\n");
  EXPECT_NE(errorOf("stereo_match: {min_zncc: 0.7, min_zncc: 0.8}\n")
                .find("duplicate key 'stereo_match.min_zncc'"),
            std::string::npos);
  // Two sections of the same name (the second would silently replace or be ignored).
  EXPECT_NE(errorOf("motion: {ransac: true}\nthreads: 2\nmotion: {ransac: false}\n")
                .find("duplicate key 'motion'"),
            std::string::npos);
}

TEST(RunConfig, AValueWhereASectionIsExpectedIsNamed) {
  const std::string e = errorOf("detector: 5\n");
  EXPECT_NE(e.find("key 'detector' must be a mapping"), std::string::npos) << e;
  EXPECT_EQ(e.find("unknown key"), std::string::npos) << e;
  EXPECT_NE(errorOf("stereo_match: [1, 2]\n").find("'stereo_match' must be a mapping"),
            std::string::npos);
}

TEST(RunConfig, LargeConfigIsRejectedWithTheFirstUnknownKey) {
  // About 400 KB: the known sections, then 22 000 keys of an unknown one. Each read is a lookup
  // in the index made when the file is loaded (it used to copy the whole tree per key: 30 s).
  std::string yaml = "seed: 3\nstereo_match: {min_zncc: 0.7}\nextra:\n";
  for (int i = 0; i < 22000; ++i) yaml += "  key_" + std::to_string(100000 + i) + ": 1.0\n";
  ASSERT_GT(yaml.size(), 380000u);
  const std::string e = errorOf(yaml);
  EXPECT_NE(e.find("unknown key 'extra.key_100000'"), std::string::npos) << e;
}

TEST(RunConfig, ADirectoryIsNotAConfigFile) {
  RunConfig c;
  const std::string dir = ::testing::TempDir();
  const svslam::Status s = svslam::config::loadRunConfig(dir, c);
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.message().find(dir), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("is a directory"), std::string::npos) << s.message();
}

TEST(RunConfig, BadValuesAreNamed) {
  EXPECT_NE(errorOf("stereo_match: {min_zncc: 3}\n").find("'stereo_match.min_zncc'"),
            std::string::npos);
  EXPECT_NE(errorOf("threads: two\n").find("'threads'"), std::string::npos);
  EXPECT_NE(errorOf("stereo_match: {sigma_mode: median}\n").find("'stereo_match.sigma_mode'"),
            std::string::npos);
  EXPECT_NE(errorOf("stereo_match: {min_sigma_d_px: -1}\n").find("'stereo_match.min_sigma_d_px'"),
            std::string::npos);
  EXPECT_NE(errorOf("threads: 0\n").find("out of range"), std::string::npos);
  EXPECT_NE(errorOf("motion: {ransac: maybe}\n").find("'motion.ransac'"), std::string::npos);
  EXPECT_NE(errorOf("detector: {response: fast}\n").find("harris"), std::string::npos);
  EXPECT_NE(errorOf("seed: -1\n").find("'seed'"), std::string::npos);
  EXPECT_NE(errorOf("odometry: {max_depth_m: .nan}\n").find("'odometry.max_depth_m'"),
            std::string::npos);
  EXPECT_NE(errorOf("stereo_match: {min_disp_px: 50, max_disp_px: 40}\n")
                .find("stereo_match.max_disp_px"),
            std::string::npos);
  EXPECT_NE(errorOf("dense_stereo: {enabled: true, window_w_px: 4}\n").find("dense_stereo"),
            std::string::npos);
  EXPECT_NE(errorOf("dense_stereo: {enabled: true}\nodometry: {match_sigma_px: 0.7}\n")
                .find("match_sigma_px"),
            std::string::npos);
}

TEST(RunConfig, NotYamlOrNotAMap) {
  EXPECT_NE(errorOf("a: [1, 2\n").find("not valid YAML"), std::string::npos);
  EXPECT_NE(errorOf("- 1\n- 2\n").find("top level"), std::string::npos);
}

TEST(RunConfig, MissingFileIsNamed) {
  RunConfig c;
  const svslam::Status s = svslam::config::loadRunConfig("/nonexistent/svslam.yaml", c);
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.message().find("/nonexistent/svslam.yaml"), std::string::npos);
}

TEST(RunConfig, ExampleConfigLoadsAtDefaults) {
  // config/svslam.yaml documents the keys at their defaults: it must load and change nothing.
  RunConfig c, d;
  const std::string path = std::string(SVSLAM_SOURCE_DIR) + "/config/svslam.yaml";
  ASSERT_TRUE(svslam::config::loadRunConfig(path, c).isOk());
  EXPECT_EQ(c.odometry.stereo_match.max_disp_px, d.odometry.stereo_match.max_disp_px);
  EXPECT_EQ(c.odometry.corners.max_per_cell, d.odometry.corners.max_per_cell);
  EXPECT_EQ(c.odometry.temporal_match.group_size, d.odometry.temporal_match.group_size);
  EXPECT_EQ(c.odometry.dense, d.odometry.dense);
}

TEST(RunConfig, RealCameraConfigLoads) {
  // config/real_camera.yaml (docs/odometry.md): the ORB front end with RANSAC motions.
  RunConfig c;
  const std::string path = std::string(SVSLAM_SOURCE_DIR) + "/config/real_camera.yaml";
  ASSERT_TRUE(svslam::config::loadRunConfig(path, c).isOk());
  EXPECT_EQ(c.odometry.detector, svslam::PointDetector::kOrb);
  EXPECT_TRUE(c.odometry.motion.ransac);
  EXPECT_TRUE(c.odometry.repredict);
}

TEST(RunConfig, ExampleConfigChangesNoDefault) {
  // Every key of config/svslam.yaml must hold the code's default (the file documents them): a
  // value that differs (stereo_match.refine_iterations was 6 against a default of 10) is named.
  RunConfig c;
  std::set<std::string> changed;
  const std::string path = std::string(SVSLAM_SOURCE_DIR) + "/config/svslam.yaml";
  ASSERT_TRUE(svslam::config::loadRunConfig(path, c, &changed).isOk());
  std::string list;
  for (const std::string& k : changed) list += " " + k;
  EXPECT_TRUE(changed.empty()) << "keys that differ from the defaults:" << list;
}

TEST(ConfigReader, ChangedKeysAreThoseThatDifferFromTheTarget) {
  auto r = ConfigReader::fromString("a: 0.8\nb: 3\nc: 0.25\nd: true\ne: x\nf: [1, 2]\n", "x");
  ASSERT_TRUE(r.isOk());
  float a = 0.8f;  // the same value through float: not a change
  int b = 4;
  double c = 0.25;
  bool d = false;
  std::string e = "x";
  std::vector<double> f{1, 2};
  ASSERT_TRUE(r->read("a", a, 0, 1).isOk());
  ASSERT_TRUE(r->read("b", b, 0, 10).isOk());
  ASSERT_TRUE(r->read("c", c, 0, 1).isOk());
  ASSERT_TRUE(r->read("d", d).isOk());
  ASSERT_TRUE(r->read("e", e).isOk());
  ASSERT_TRUE(r->read("f", f).isOk());
  EXPECT_EQ(r->changedKeys(), (std::set<std::string>{"b", "d"}));
}

TEST(ConfigReader, TypedReads) {
  auto r = ConfigReader::fromString("a: {b: 2.5, c: [1, 2, 3]}\nn: 7\n", "x");
  ASSERT_TRUE(r.isOk());
  double b = 0;
  std::vector<double> c;
  int n = 0, absent = 5;
  EXPECT_TRUE(r->read("a.b", b, 0, 10).isOk());
  EXPECT_TRUE(r->read("a.c", c).isOk());
  EXPECT_TRUE(r->read("n", n, 0, 10).isOk());
  EXPECT_TRUE(r->read("zz", absent, 0, 10).isOk());
  EXPECT_EQ(b, 2.5);
  EXPECT_EQ(c.size(), 3u);
  EXPECT_EQ(n, 7);
  EXPECT_EQ(absent, 5);  // absent keys leave the value alone
  EXPECT_TRUE(r->finish().isOk());
}

TEST(RunConfig, LcmCommandsAreOffByDefaultAndNeedATokenFile) {
  RunConfig d;
  EXPECT_FALSE(d.lcm.commands.enabled);
  EXPECT_EQ(d.lcm.commands.token_file, "");
  EXPECT_EQ(d.lcm.commands.max_per_s, 10.0);
  RunConfig c;
  ASSERT_TRUE(parseRunConfig("lcm: {commands: {enabled: true, token_file: /run/t, max_per_s: 2}}\n",
                             "t.yaml", c)
                  .isOk());
  EXPECT_TRUE(c.lcm.commands.enabled);
  EXPECT_EQ(c.lcm.commands.token_file, "/run/t");
  EXPECT_EQ(c.lcm.commands.max_per_s, 2.0);
  EXPECT_NE(errorOf("lcm: {commands: {enabled: true}}\n").find("lcm.commands.token_file"),
            std::string::npos)
      << errorOf("lcm: {commands: {enabled: true}}\n");
  EXPECT_NE(errorOf("lcm: {commands: {max_per_s: 0}}\n").find("'lcm.commands.max_per_s'"),
            std::string::npos);
  EXPECT_NE(errorOf("lcm: {commands: {token: abc}}\n").find("lcm.commands.token"),
            std::string::npos);  // unknown key: the token never goes in the config
}

TEST(RunConfig, StallFaultIsOffByDefaultAndChecked) {
  RunConfig d;
  EXPECT_EQ(d.pipeline.fault.stall_stage, svslam::config::FaultStage::kNone);
  RunConfig c;
  ASSERT_TRUE(parseRunConfig("pipeline: {fault: {stall_stage: mapper, stall_frame: 3, "
                             "stall_ms: 2500}}\n",
                             "t.yaml", c)
                  .isOk());
  EXPECT_EQ(c.pipeline.fault.stall_stage, svslam::config::FaultStage::kMapper);
  EXPECT_EQ(c.pipeline.fault.stall_frame, 3);
  EXPECT_EQ(c.pipeline.fault.stall_ms, 2500);
  EXPECT_NE(errorOf("pipeline: {fault: {stall_stage: vme}}\n").find("'pipeline.fault.stall_stage'"),
            std::string::npos);
  EXPECT_NE(errorOf("pipeline: {fault: {stall_ms: 0}}\n").find("'pipeline.fault.stall_ms'"),
            std::string::npos);
  EXPECT_NE(errorOf("pipeline: {fault: {stall_frame: -1}}\n").find("'pipeline.fault.stall_frame'"),
            std::string::npos);
}

// An alias inside the map it names recursed without end while the keys were indexed (stack
// overflow, found with fuzz_yaml_config): now an error, as is any nesting deeper than kMaxDepth.
TEST(RunConfig, RecursiveAliasIsAnError) {
  EXPECT_NE(errorOf("a: &d\n  b: *d\n").find("nested more than"), std::string::npos);
  std::string deep;
  for (int i = 0; i <= svslam::config::ConfigReader::kMaxDepth + 1; ++i) deep += "{k: ";
  deep += "1";
  for (int i = 0; i <= svslam::config::ConfigReader::kMaxDepth + 1; ++i) deep += "}";
  EXPECT_NE(errorOf(deep + "\n").find("nested more than"), std::string::npos);
}

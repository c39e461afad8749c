// The configuration declared once: config/svslam.yaml is exactly `svslam config --defaults`,
// the printed file reads back to the defaults (and any printed config to its values, floats
// exactly), renamed keys name their new name, choices read into enums.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "cli_helpers.hpp"
#include "pipeline/config/config_keys.hpp"
#include "pipeline/config/run_config.hpp"

using namespace svslam::config;
using svslam::test::slurp;

namespace {

// stdout of `svslam <args>`, and its exit code.
std::string runCli(const std::string& args, int& code) {
  std::string out;
  FILE* p = ::popen((std::string(SVSLAM_CLI) + " " + args + " 2>/dev/null").c_str(), "r");
  if (!p) return out;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  const int status = ::pclose(p);
  code = svslam::test::exitCode(status);
  return out;
}

// The first line where `a` and `b` differ, for the failure message.
std::string firstDifference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb;
  for (int n = 1;; ++n) {
    const bool ea = !std::getline(sa, la), eb = !std::getline(sb, lb);
    if (ea && eb) return "same lines (line endings differ?)";
    if (ea || eb || la != lb)
      return "line " + std::to_string(n) + ":\n  file:    " + (ea ? "<end>" : la) +
             "\n  printed: " + (eb ? "<end>" : lb);
  }
}

const std::string kExample = std::string(SVSLAM_SOURCE_DIR) + "/config/svslam.yaml";

}  // namespace

TEST(ConfigDefaults, ExampleFileIsThePrintedDefaults) {
  const std::string file = slurp(kExample);
  ASSERT_FALSE(file.empty()) << kExample;
  EXPECT_TRUE(file == defaultsYaml())
      << "config/svslam.yaml differs from the declarations; regenerate it with\n"
         "  svslam config --defaults > config/svslam.yaml\nFirst difference at "
      << firstDifference(file, defaultsYaml());
}

TEST(ConfigDefaults, ExampleFileIsTheCliOutput) {
  if (std::string(SVSLAM_CLI).empty()) GTEST_SKIP() << "the svslam executable is not built";
  int code = -1;
  const std::string printed = runCli("config --defaults", code);
  EXPECT_EQ(code, 0);
  const std::string file = slurp(kExample);
  EXPECT_TRUE(file == printed)
      << "config/svslam.yaml differs from `svslam config --defaults`; regenerate it with\n"
         "  svslam config --defaults > config/svslam.yaml\nFirst difference at "
      << firstDifference(file, printed);
}

TEST(ConfigDefaults, CliNeedsDefaultsFlagAndChecksMode) {
  if (std::string(SVSLAM_CLI).empty()) GTEST_SKIP() << "the svslam executable is not built";
  int code = -1;
  EXPECT_TRUE(runCli("config", code).empty());
  EXPECT_EQ(code, 2);
  runCli("run --mode slam --max-frames 1", code);
  EXPECT_EQ(code, 1);  // rejected by the one check of --mode, before anything runs
}

TEST(ConfigDefaults, PrintedDefaultsReadBackUnchanged) {
  RunConfig c;
  std::set<std::string> changed;
  ASSERT_TRUE(parseRunConfig(defaultsYaml(), "defaults.yaml", c, &changed).isOk());
  std::string list;
  for (const std::string& k : changed) list += " " + k;
  EXPECT_TRUE(changed.empty()) << "keys read back to another value:" << list;
  EXPECT_EQ(formatRunConfig(c), formatRunConfig(RunConfig{}));
}

TEST(ConfigDefaults, AnyPrintedConfigReadsBackExactly) {
  RunConfig c;
  c.source = "kitti:/data/my seq #1: \"x\"";  // needs quoting
  c.seed = 18446744073709551615ull;
  c.mode = EstimatorMode::kVo;
  c.odometry.stereo_match.min_zncc = 0.7123457f;
  c.odometry.motion.ransac_chi2 = 0.1 + 0.2;  // 0.30000000000000004
  c.odometry.max_depth_m = 1.0 / 3.0 * 1e7;
  c.slam.lost_rot_sigma_rad = 1.2345678901234567e-5;
  c.odometry.dense_stereo.max_disp = 96;
  c.odometry.clusters.roi_radius = svslam::RoiRadius::kFarthestPoint;
  c.pipeline.capture_policy = CapturePolicy::kBlock;
  c.pipeline.estimator.cpus = {0, 3};
  c.service.ready = ReadyWhen::kStart;
  const std::string text = formatRunConfig(c);
  RunConfig d;
  ASSERT_TRUE(parseRunConfig(text, "printed.yaml", d).isOk()) << text;
  EXPECT_EQ(formatRunConfig(d), text);
  EXPECT_EQ(d.source, c.source);
  EXPECT_EQ(d.seed, c.seed);
  EXPECT_EQ(d.odometry.stereo_match.min_zncc, c.odometry.stereo_match.min_zncc);
  EXPECT_EQ(d.odometry.motion.ransac_chi2, c.odometry.motion.ransac_chi2);
  EXPECT_EQ(d.odometry.max_depth_m, c.odometry.max_depth_m);
  EXPECT_EQ(d.slam.lost_rot_sigma_rad, c.slam.lost_rot_sigma_rad);
  EXPECT_EQ(d.odometry.dense_stereo.max_disp, 96);
  EXPECT_EQ(d.pipeline.estimator.cpus, (std::vector<int>{0, 3}));
  EXPECT_EQ(d.service.ready, ReadyWhen::kStart);
}

TEST(ConfigDefaults, EveryKeyDeclaredOnceWithDoc) {
  std::set<std::string> seen;
  for (const ConfigSection& s : allConfigSections())
    for (const ConfigKey& k : s.keys) {
      const std::string name = s.name.empty() ? k.name : s.name + "." + k.name;
      EXPECT_TRUE(seen.insert(name).second) << name << " declared twice";
      EXPECT_FALSE(k.doc.empty()) << name;
      EXPECT_TRUE(k.read && k.value) << name;
    }
  for (const RenamedKey& r : renamedConfigKeys()) {
    EXPECT_EQ(seen.count(r.old_name), 0u) << r.old_name;
    EXPECT_EQ(seen.count(r.new_name), 1u) << r.new_name;
  }
}

TEST(ConfigDefaults, RenamedKeysNameTheNewName) {
  RunConfig c;
  const svslam::Status s =
      parseRunConfig("dense_stereo: {enabled: true, max_disp: 96}\n", "config.yaml", c);
  ASSERT_FALSE(s.isOk());
  EXPECT_EQ(s.message(),
            "config.yaml: key 'dense_stereo.max_disp' was renamed to 'dense_stereo.max_disp_px'");
  for (const RenamedKey& r : renamedConfigKeys()) {
    const std::string old_name = r.old_name;
    const std::string yaml = old_name.substr(0, old_name.find('.')) + ": {" +
                             old_name.substr(old_name.find('.') + 1) + ": 1}\n";
    const svslam::Status e = parseRunConfig(yaml, "c.yaml", c);
    EXPECT_NE(e.message().find(std::string("renamed to '") + r.new_name + "'"), std::string::npos)
        << yaml << " -> " << e.message();
  }
}

TEST(ConfigDefaults, ChoicesReadIntoEnums) {
  RunConfig c;
  ASSERT_TRUE(parseRunConfig("mode: vo\npipeline: {capture_policy: newest}\n"
                             "service: {ready: start}\n",
                             "e.yaml", c)
                  .isOk());
  EXPECT_EQ(c.mode, EstimatorMode::kVo);
  EXPECT_EQ(c.pipeline.capture_policy, CapturePolicy::kNewest);
  EXPECT_EQ(c.service.ready, ReadyWhen::kStart);
  EXPECT_STREQ(toString(c.mode), "vo");
  EXPECT_STREQ(toString(EstimatorMode::kEkf), "ekf");
  EXPECT_STREQ(toString(CapturePolicy::kBlock), "block");
  EXPECT_STREQ(toString(ReadyWhen::kFirstPose), "first_pose");
  const svslam::Status s = parseRunConfig("mode: slam\n", "e.yaml", c);
  EXPECT_NE(s.message().find("'mode' = 'slam' is not one of: ekf, vo"), std::string::npos)
      << s.message();
  RunConfig d;
  EXPECT_EQ(d.mode, EstimatorMode::kEkf);
  EXPECT_EQ(d.pipeline.capture_policy, CapturePolicy::kAuto);
  EXPECT_EQ(d.service.ready, ReadyWhen::kFirstPose);
}

TEST(ConfigDefaults, ThreadsSetTheStripes) {
  RunConfig c;
  applyThreads(c, 3);
  EXPECT_EQ(c.threads, 3);
  EXPECT_EQ(c.odometry.dense_stereo.num_stripes, 3);
  RunConfig d;
  ASSERT_TRUE(parseRunConfig("threads: 4\n", "t.yaml", d).isOk());
  EXPECT_EQ(d.odometry.dense_stereo.num_stripes, 4);
}

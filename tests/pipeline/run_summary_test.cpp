// stats.json: the source's counters (live cameras: reconnects, frames lost, drops, frozen) appear
// under "source_counters" in the source's order, and the key is absent for sources without any;
// the innovation statistics are per degree of freedom over the frames that have them.
#include "pipeline/run/run_summary.hpp"

#include <gtest/gtest.h>

#include <string>

namespace svslam::run {
namespace {

std::string stats(const RunSummary& s, EstimatorOutputs outputs = {}) {
  config::RunConfig cfg;
  return statsJson(cfg, "v4l2:/dev/video0,/dev/video1", s, outputs, StageTimes(1),
                   rt::PipelineReport{}, "");
}

TEST(RunSummary, SourceCountersAreWrittenInOrder) {
  RunSummary s;
  s.source_counters = {{"reconnects", 1}, {"reconnect_frames_lost", 7}, {"left_frozen", 0}};
  const std::string j = stats(s);
  EXPECT_NE(j.find("\"source_counters\": {\"reconnects\": 1, \"reconnect_frames_lost\": 7, "
                   "\"left_frozen\": 0}"),
            std::string::npos)
      << j;
}

TEST(RunSummary, NoSourceCountersNoKey) {
  EXPECT_EQ(stats(RunSummary{}).find("source_counters"), std::string::npos);
}

TEST(RunSummary, InnovationStatisticsArePerDegreeOfFreedom) {
  RunSummary s;
  SlamFrameResult first;  // frame 0: tracked, no motion, no observation
  first.odometry.tracked = true;
  s.add(0, first);
  SlamFrameResult a;
  a.odometry.tracked = true;
  a.odometry.inliers = 50;
  a.odometry.motion_rms_mahalanobis = 2.0;  // mean squared 4 over 3 dof
  a.nis_sum = 9.0;                          // 2 observations, 6 dof
  a.nis_count = 2;
  s.add(1, a);
  SlamFrameResult b = a;
  b.odometry.motion_rms_mahalanobis = 1.0;  // mean squared 1
  b.nis_sum = 3.0;                          // 2 observations
  s.add(2, b);
  SlamFrameResult lost;  // not tracked: no motion residual
  lost.odometry.motion_rms_mahalanobis = 100.0;
  s.add(3, lost);
  const std::string j = stats(s, EstimatorOutputs{true, true});
  // (4 + 1) / 2 / 3 and (9 + 3) / (4 * 3)
  EXPECT_NE(j.find("\"motion_residual_per_dof\": 0.833"), std::string::npos) << j;
  EXPECT_NE(j.find("\"observation_nis_per_dof\": 1.000"), std::string::npos) << j;
  // Without a landmark map no observation statistic; with no motion estimated, 0.
  const std::string none = stats(RunSummary{});
  EXPECT_EQ(none.find("observation_nis_per_dof"), std::string::npos) << none;
  EXPECT_NE(none.find("\"motion_residual_per_dof\": 0.000"), std::string::npos) << none;
}

}  // namespace
}  // namespace svslam::run

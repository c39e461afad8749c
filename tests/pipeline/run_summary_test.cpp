// stats.json: the source's counters (live cameras: reconnects, frames lost, drops, frozen) appear
// under "source_counters" in the source's order, and the key is absent for sources without any.
#include "pipeline/run/run_summary.hpp"

#include <gtest/gtest.h>

#include <string>

namespace svslam::run {
namespace {

std::string stats(const RunSummary& s) {
  config::RunConfig cfg;
  return statsJson(cfg, "v4l2:/dev/video0,/dev/video1", s, EstimatorOutputs{}, StageTimes(1),
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

}  // namespace
}  // namespace svslam::run

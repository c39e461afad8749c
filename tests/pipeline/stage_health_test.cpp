// Stage stalls: StageHealth's stretches and threshold on a scripted clock, then the runner with
// an injected stall (pipeline.fault's hook) in one stage of a scripted graph, threaded and
// sequential: the health check sees that stage stalled while it sleeps (and no other, the stage
// waiting for its feedback included), and the report counts exactly one stall of it.
#include "pipeline/realtime/stage_health.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>

#include "pipeline/realtime/edges.hpp"
#include "pipeline/realtime/fault_injection.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "scripted_graph.hpp"

using namespace std::chrono_literals;

namespace svslam::rt {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(StageHealth, StretchesBeyondTheThresholdAreStalls) {
  StageHealth h({"capture", "stereo", "estimator"});
  h.setStallThresholdNs(100 * kMs);
  h.begin(1, 1000 * kMs);
  h.end(1, 1050 * kMs);  // 50 ms: not a stall
  h.begin(2, 1000 * kMs);
  HealthSnapshot s = h.snapshot(1080 * kMs);
  EXPECT_EQ(s.stalled_stage, "");
  EXPECT_TRUE(s.stalls.empty());
  s = h.snapshot(1250 * kMs);  // estimator busy for 250 ms: stalled now
  EXPECT_EQ(s.stalled_stage, "estimator");
  EXPECT_DOUBLE_EQ(s.stalled_ms, 250.0);
  ASSERT_EQ(s.stalls.size(), 1u);
  EXPECT_EQ(s.stalls[0].stage, "estimator");
  EXPECT_EQ(s.stalls[0].count, 1);
  EXPECT_DOUBLE_EQ(s.stalls[0].longest_ms, 250.0);
  h.begin(0, 1100 * kMs);  // capture busy for 150 ms at 1250: stalled too, but less long
  s = h.snapshot(1250 * kMs);
  EXPECT_EQ(s.stalled_stage, "estimator");
  EXPECT_EQ(s.totalStalls(), 2);
  h.end(0, 1150 * kMs);
  h.end(2, 1400 * kMs);  // the stall ends after 400 ms
  s = h.snapshot(5000 * kMs);
  EXPECT_EQ(s.stalled_stage, "");
  EXPECT_EQ(s.stalled_ms, 0.0);
  ASSERT_EQ(s.stalls.size(), 1u);  // capture's stretch ended after 50 ms
  EXPECT_EQ(s.stalls[0].count, 1);
  EXPECT_DOUBLE_EQ(s.stalls[0].longest_ms, 400.0);
  h.reset();
  EXPECT_TRUE(h.snapshot(6000 * kMs).stalls.empty());
}

TEST(StageHealth, NoThresholdNoStall) {
  StageHealth h({"a"});
  h.begin(0, 1);
  h.end(0, 10'000 * kMs);
  EXPECT_TRUE(h.snapshot(20'000 * kMs).stalls.empty());
}

TEST(StageHealth, AWaitEndsTheStretch) {
  StageHealth h({"a", "b"});
  h.setStallThresholdNs(50 * kMs);
  {
    StageWork work(h, 1);
    {
      StageWait wait;  // 120 ms waiting for another stage: not b's stall
      std::this_thread::sleep_for(120ms);
      EXPECT_EQ(h.snapshot(steadyNowNs()).stalled_stage, "");
    }
  }
  EXPECT_TRUE(h.snapshot(steadyNowNs()).stalls.empty());
  {
    StageWork work(h, 1);
    std::this_thread::sleep_for(120ms);
    EXPECT_EQ(h.snapshot(steadyNowNs()).stalled_stage, "b");
  }
  const HealthSnapshot s = h.snapshot(steadyNowNs());
  ASSERT_EQ(s.stalls.size(), 1u);
  EXPECT_EQ(s.stalls[0].stage, "b");
  EXPECT_GE(s.stalls[0].longest_ms, 120.0);
  StageWait outside;  // no StageWork on this thread: nothing happens
}

// capture -> stereo -> estimator -> publisher; the stereo stage of frame k waits (StageWait)
// for the estimator's feedback on frame k - 1, as svslam's ROI tracking does.
struct FeedbackWork {
  int frames = 40;
  int next = 0;
  std::int64_t last_stereo = -1;
  FeedbackCell<int> feedback;
  std::atomic<int> published{0};
  Result<bool> capture(FrameSlot& s) {
    if (next >= frames) return false;
    s.frame.index = next++;
    std::this_thread::sleep_for(1ms);
    return true;
  }
  Status stereo(FrameSlot& s) {
    if (last_stereo >= 0) {
      int fb = 0;
      StageWait waiting;
      if (!feedback.wait(last_stereo, fb)) return Status::failedPrecondition("closed");
    }
    last_stereo = s.seq;
    return Status::ok();
  }
  Status estimate(FrameSlot& s) {
    feedback.publish(s.seq, s.frame.index);
    return Status::ok();
  }
  Status publish(FrameSlot&) {
    ++published;
    return Status::ok();
  }
};

// Runs the graph with `fault`; returns the report and whether the health check (the tick, every
// 10 ms) saw `fault.stage` stalled, and any other stage stalled.
struct StallRun {
  PipelineReport report;
  bool saw_stage = false;
  std::string other;
};

StallRun runWithStall(bool sequential, const StallFault& fault) {
  FeedbackWork work;
  StageGraph g = fourStageGraph(work);
  EXPECT_TRUE(injectStall(g, fault).isOk());
  PipelineOptions o;
  o.sequential = sequential;
  PipelineRunner runner(o, std::move(g));
  runner.setStallThresholdNs(300 * kMs);
  PipelineControl control;
  auto slots = makeSlots(runner);
  StallRun r;
  auto tick = [&] {
    const HealthSnapshot h = runner.health().snapshot(steadyNowNs());
    if (h.stalled_stage == fault.stage && !fault.stage.empty()) r.saw_stage = true;
    if (!h.stalled_stage.empty() && h.stalled_stage != fault.stage) r.other = h.stalled_stage;
  };
  EXPECT_TRUE(runner.run(slots, control, tick, 10).isOk());
  r.report = runner.report();
  EXPECT_EQ(work.published.load(), work.frames);
  return r;
}

TEST(PipelineStall, TheStalledStageIsNamedAndCountedOnce) {
  for (const char* stage : {"capture", "stereo", "estimator", "publisher"}) {
    SCOPED_TRACE(stage);
    const StallRun r = runWithStall(false, {stage, 10, 1000});
    EXPECT_TRUE(r.saw_stage);
    EXPECT_EQ(r.other, "");  // the stereo stage waiting for a stalled estimator is not stalled
    const HealthSnapshot& h = r.report.health;
    EXPECT_EQ(h.stalled_stage, "");  // over by the end of the run
    EXPECT_EQ(r.report.stall_threshold_ns, 300 * kMs);
    ASSERT_EQ(h.stalls.size(), 1u);
    EXPECT_EQ(h.stalls[0].stage, stage);
    EXPECT_EQ(h.stalls[0].count, 1);
    EXPECT_GE(h.stalls[0].longest_ms, 1000.0);
    EXPECT_LT(h.stalls[0].longest_ms, 30000.0);
  }
}

TEST(PipelineStall, SequentialRunCountsTheStallAfterwards) {
  const StallRun r = runWithStall(true, {"estimator", 5, 600});
  const HealthSnapshot& h = r.report.health;
  ASSERT_EQ(h.stalls.size(), 1u);
  EXPECT_EQ(h.stalls[0].stage, "estimator");
  EXPECT_EQ(h.stalls[0].count, 1);
  EXPECT_GE(h.stalls[0].longest_ms, 600.0);
}

TEST(PipelineStall, NoFaultNoStall) {
  const StallRun r = runWithStall(false, {});
  EXPECT_EQ(r.other, "");
  EXPECT_TRUE(r.report.health.stalls.empty());
  EXPECT_EQ(r.report.health.totalStalls(), 0);
}

TEST(PipelineStall, UnknownStageIsRefusedNamingIt) {
  FeedbackWork work;
  StageGraph g = fourStageGraph(work);
  const Status s = injectStall(g, {"mapper", 0, 100});
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.message().find("'mapper'"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("capture, stereo, estimator, publisher"), std::string::npos)
      << s.message();
  EXPECT_FALSE(injectStall(g, {"stereo", 0, 0}).isOk());
  EXPECT_TRUE(injectStall(g, {}).isOk());
}

}  // namespace
}  // namespace svslam::rt

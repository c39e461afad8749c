// A stage after publication (StageSpec::after_publish, the mapper's place): frames are published
// before it runs; with a newest-frame input a slow side stage skips frames and counts them
// without delaying any pose; with a blocking input (and sequentially) it sees every frame.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "pipeline/realtime/pipeline_runner.hpp"
#include "scripted_graph.hpp"

namespace svslam::rt {
namespace {

using namespace std::chrono_literals;

struct SideWork {
  int frames = 0;
  std::chrono::microseconds side_cost{0};
  int next = 0;
  std::vector<int> published, mapped;
  Result<bool> capture(FrameSlot& s) {
    if (next >= frames) return false;
    s.frame.index = next++;
    return true;
  }
  Status stereo(FrameSlot&) { return Status::ok(); }
  Status estimate(FrameSlot&) { return Status::ok(); }
  Status publish(FrameSlot& s) {
    published.push_back(s.frame.index);
    return Status::ok();
  }
  Status map(FrameSlot& s) {
    // Publication comes first: this frame has already been published.
    if (s.frame.index >= static_cast<int>(published_count.load()))
      return Status::failedPrecondition("mapped before published");
    if (side_cost.count() > 0) std::this_thread::sleep_for(side_cost);
    mapped.push_back(s.frame.index);
    return Status::ok();
  }
  std::atomic<std::int64_t> published_count{0};
  StageGraph graph(EdgePolicy side_input) {
    StageGraph g = fourStageGraph(*this);
    auto pub = g.stages.back().work;
    g.stages.back().work = [this, pub](FrameSlot& s) {
      const Status st = pub(s);
      published_count = s.frame.index + 1;
      return st;
    };
    StageSpec side{"mapper", [this](FrameSlot& s) { return map(s); }, side_input};
    side.after_publish = true;
    g.stages.push_back(side);
    return g;
  }
};

TEST(AfterPublish, SlowSideStageSkipsAndCountsWithoutDelayingPoses) {
  SideWork w;
  w.frames = 300;
  w.side_cost = 3000us;
  PipelineOptions o;
  o.rate_hz = 1000.0;  // a frame every 1 ms; the side stage needs 3 ms
  PipelineRunner runner(o, w.graph(EdgePolicy::kNewest));
  auto slots = makeSlots(runner);
  PipelineControl control;
  ASSERT_TRUE(runner.run(slots, control, nullptr).isOk()) << runner.report().error.message();
  const PipelineReport& r = runner.report();
  EXPECT_EQ(r.published, 300);  // every pose, none dropped for the side stage
  EXPECT_EQ(r.dropped, 0);
  EXPECT_GT(r.after_publish_skipped, 100);
  EXPECT_EQ(static_cast<std::int64_t>(w.mapped.size()) + r.after_publish_skipped, 300);
  for (std::size_t i = 1; i < w.mapped.size(); ++i) EXPECT_GT(w.mapped[i], w.mapped[i - 1]);
  EXPECT_EQ(w.mapped.back(), 299);  // the newest frame is mapped
  EXPECT_EQ(r.stages.size(), 4u);   // capture, stereo, estimator, publisher: the side is untimed
}

TEST(AfterPublish, BlockingSideStageAndSequentialSeeEveryFrame) {
  for (bool sequential : {false, true}) {
    SideWork w;
    w.frames = 100;
    w.side_cost = 200us;
    PipelineOptions o;
    o.sequential = sequential;
    PipelineRunner runner(o, w.graph(EdgePolicy::kBlocking));
    auto slots = makeSlots(runner);
    PipelineControl control;
    ASSERT_TRUE(runner.run(slots, control, nullptr).isOk()) << runner.report().error.message();
    EXPECT_EQ(runner.report().published, 100);
    EXPECT_EQ(runner.report().after_publish_skipped, 0);
    ASSERT_EQ(w.mapped.size(), 100u) << (sequential ? "sequential" : "threaded");
    for (int i = 0; i < 100; ++i) EXPECT_EQ(w.mapped[static_cast<std::size_t>(i)], i);
  }
}

TEST(AfterPublish, OnlyTheLastStageMayRunAfterPublication) {
  SideWork w;
  StageGraph g = w.graph(EdgePolicy::kNewest);
  std::swap(g.stages[2], g.stages[3]);  // side stage before the publisher
  EXPECT_FALSE(g.validate().isOk());
  StageGraph ok = w.graph(EdgePolicy::kNewest);
  EXPECT_TRUE(ok.validate().isOk());
}

}  // namespace
}  // namespace svslam::rt

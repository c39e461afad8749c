// The real-time pipeline's edges and runner, with a scripted work whose outputs depend on the
// order of frames (so a reordering, a lost frame or a race shows up), then `svslam run` threaded
// against --sequential byte for byte.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "cli_helpers.hpp"
#include "pipeline/realtime/edges.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "scripted_graph.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace svslam::rt {
namespace {

using test::slurp;

TEST(BlockingEdge, KeepsOrderAndEndsAfterClose) {
  BlockingEdge<int> e(3);
  int v[5] = {0, 1, 2, 3, 4};
  std::thread producer([&] {
    for (int& x : v) e.push(&x);
    e.close();
  });
  std::vector<int> got;
  for (;;) {
    int* p = nullptr;
    if (!e.pop(p, 100ms)) continue;
    if (!p) break;
    got.push_back(*p);
  }
  producer.join();
  EXPECT_EQ(got, (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_LE(e.maxDepth(), 3);
  EXPECT_EQ(e.drops(), 0);
}

TEST(BlockingEdge, PopTimesOutWhenEmpty) {
  BlockingEdge<int> e(2);
  int* p = reinterpret_cast<int*>(1);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(e.pop(p, 20ms));
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 15ms);
  EXPECT_EQ(p, reinterpret_cast<int*>(1));
}

TEST(NewestEdge, ReplacesTheWaitingItemAndCountsTheDrop) {
  NewestEdge<int> e;
  int a = 1, b = 2, c = 3;
  EXPECT_EQ(e.push(&a), nullptr);
  EXPECT_EQ(e.push(&b), &a);  // a handed back to the producer
  EXPECT_EQ(e.push(&c), &b);
  EXPECT_EQ(e.drops(), 2);
  int* p = nullptr;
  ASSERT_TRUE(e.pop(p, 10ms));
  EXPECT_EQ(p, &c);
  EXPECT_FALSE(e.pop(p, 10ms));
  e.close();
  ASSERT_TRUE(e.pop(p, 10ms));
  EXPECT_EQ(p, nullptr);
}

TEST(NewestEdge, ConcurrentProducerConsumerLoseNothingUncounted) {
  NewestEdge<int> e;
  constexpr int kN = 20000;
  std::vector<int> items(kN);
  for (int i = 0; i < kN; ++i) items[static_cast<std::size_t>(i)] = i;
  std::atomic<int> handed_back{0};
  std::thread producer([&] {
    for (int& x : items)
      if (e.push(&x)) ++handed_back;
    e.close();
  });
  int received = 0, last = -1;
  bool ordered = true;
  for (;;) {
    int* p = nullptr;
    if (!e.pop(p, 100ms)) continue;
    if (!p) break;
    ordered = ordered && *p > last;
    last = *p;
    ++received;
  }
  producer.join();
  EXPECT_TRUE(ordered);
  EXPECT_EQ(last, kN - 1);  // the newest always arrives
  EXPECT_EQ(received + handed_back.load(), kN);
  EXPECT_EQ(e.drops(), handed_back.load());
}

// A scripted pipeline: capture writes the frame number into the image, stereo derives a value
// from it, estimate folds it into a running state (order-dependent), publish records it.
class ScriptedWork {
 public:
  explicit ScriptedWork(int frames, std::chrono::microseconds stereo_cost = 0us)
      : frames_(frames), stereo_cost_(stereo_cost) {}
  Result<bool> capture(FrameSlot& slot) {
    if (next_ >= frames_) return false;
    if (capture_fail_at_ >= 0 && next_ == capture_fail_at_)
      return Status::corruptData("scripted unreadable frame");
    slot.frame.index = next_;
    slot.frame.t_ns = 1000 * static_cast<TimeNs>(next_);
    slot.frame.left.resize(8, 4);
    slot.frame.left.row(0)[0] = static_cast<std::uint8_t>(next_ & 0xff);
    ++next_;
    return true;
  }
  Status stereo(FrameSlot& slot) {
    if (stereo_cost_.count() > 0) std::this_thread::sleep_for(stereo_cost_);
    slot.stereo.max_response = static_cast<float>(slot.frame.left.row(0)[0]) * 2.0f + 1.0f;
    return Status::ok();
  }
  Status estimate(FrameSlot& slot) {
    if (fail_at_ >= 0 && slot.frame.index == fail_at_)
      return Status::corruptData("scripted failure");
    state_ = state_ * 31 + static_cast<std::uint64_t>(slot.stereo.max_response);
    slot.result.landmarks_in_state = static_cast<int>(state_ & 0x7fffffff);
    return Status::ok();
  }
  Status publish(FrameSlot& slot) {
    published_.push_back({slot.frame.index, slot.result.landmarks_in_state});
    return Status::ok();
  }
  StageGraph graph(EdgePolicy capture_input = EdgePolicy::kBlocking) {
    return fourStageGraph(*this, capture_input);
  }
  int fail_at_ = -1;
  int capture_fail_at_ = -1;
  std::vector<std::pair<int, int>> published_;

 private:
  int frames_;
  std::chrono::microseconds stereo_cost_;
  int next_ = 0;
  std::uint64_t state_ = 7;
};

std::vector<std::pair<int, int>> runScripted(const PipelineOptions& o, int frames,
                                             PipelineReport* report = nullptr) {
  ScriptedWork work(frames);
  PipelineRunner runner(o, work.graph());
  PipelineControl control;
  auto slots = makeSlots(runner);
  EXPECT_TRUE(runner.run(slots, control, nullptr).isOk());
  if (report) *report = runner.report();
  return work.published_;
}

TEST(PipelineRunner, ThreadedEqualsSequential) {
  PipelineOptions seq;
  seq.sequential = true;
  PipelineOptions thr;
  thr.queue_capacity = 1;  // the tightest back-pressure
  PipelineReport rep;
  const auto a = runScripted(seq, 500);
  const auto b = runScripted(thr, 500, &rep);
  ASSERT_EQ(a.size(), 500u);
  EXPECT_EQ(a, b);
  EXPECT_EQ(rep.captured, 500);
  EXPECT_EQ(rep.published, 500);
  EXPECT_EQ(rep.dropped, 0);
  EXPECT_EQ(rep.end_to_end.count, 500);
  ASSERT_EQ(rep.edges.size(), 3u);
  for (const EdgeReport& e : rep.edges) EXPECT_LE(e.max_depth, e.capacity) << e.name;
  EXPECT_EQ(rep.edges[1].name, "stereo->estimator");
  ASSERT_EQ(rep.stages.size(), 4u);  // the source and the three stages, each timed once
  for (const StageReport& st : rep.stages) EXPECT_EQ(st.latency.count, 500) << st.name;
}

// A stage graph is data: any chain of stages runs, threaded as sequentially, and a later stage
// can feed a value about each frame back to an earlier one (the estimator's motion for the
// stereo stage's ROIs) without a lock.
TEST(PipelineRunner, AnyChainWithFeedbackRunsThreadedAsSequential) {
  auto run = [](bool sequential) {
    std::int64_t next = 0, last_a = -1, state = 1;
    FeedbackCell<std::int64_t> fb;
    std::vector<std::int64_t> out;
    StageGraph g;
    g.source = {"src", [&](FrameSlot& s) -> Result<bool> {
                  if (next >= 300) return false;
                  s.frame.index = static_cast<int>(next++);
                  return true;
                }};
    g.stages = {{"a",
                 [&](FrameSlot& s) {  // needs stage c's value about the previous frame
                   std::int64_t prev = 0;
                   if (last_a >= 0 && !fb.wait(last_a, prev))
                     return Status::failedPrecondition("closed");
                   last_a = s.seq;
                   s.result.observed = static_cast<int>((prev * 7 + s.frame.index) % 100003);
                   return Status::ok();
                 }},
                {"b",
                 [](FrameSlot& s) {
                   s.result.gated = s.result.observed + 1;
                   return Status::ok();
                 }},
                {"c",
                 [&](FrameSlot& s) {
                   state = (state * 31 + s.result.gated) % 1000003;
                   fb.publish(s.seq, state);
                   return Status::ok();
                 }},
                {"d", [&](FrameSlot& s) {
                   out.push_back(s.result.gated);
                   return Status::ok();
                 }}};
    PipelineOptions o;
    o.sequential = sequential;
    o.queue_capacity = 1;
    PipelineRunner runner(o, std::move(g));
    PipelineControl control;
    auto slots = makeSlots(runner);
    EXPECT_TRUE(runner.run(slots, control, nullptr).isOk());
    EXPECT_EQ(runner.report().edges.size(), sequential ? 0u : 4u);
    return out;
  };
  const auto a = run(true), b = run(false);
  ASSERT_EQ(a.size(), 300u);
  EXPECT_EQ(a, b);
}

TEST(PipelineRunner, NewestPolicyDropsAndCountsUnderASlowStage) {
  PipelineOptions o;
  o.rate_hz = 1000.0;  // a frame every 1 ms, the stereo stage takes 4 ms
  ScriptedWork work(200, 4000us);
  PipelineRunner runner(o, work.graph(EdgePolicy::kNewest));
  PipelineControl control;
  auto slots = makeSlots(runner);
  ASSERT_TRUE(runner.run(slots, control, nullptr).isOk());
  const PipelineReport& r = runner.report();
  EXPECT_EQ(r.captured, 200);
  EXPECT_GT(r.dropped, 50);
  EXPECT_EQ(r.published + r.dropped, r.captured);
  EXPECT_EQ(static_cast<std::int64_t>(work.published_.size()), r.published);
  for (std::size_t i = 1; i < work.published_.size(); ++i)
    EXPECT_GT(work.published_[i].first, work.published_[i - 1].first);  // in order
  EXPECT_EQ(work.published_.back().first, 199);  // the newest frame is never lost
}

TEST(PipelineRunner, RatePacesCapture) {
  PipelineOptions o;
  o.rate_hz = 100.0;
  ScriptedWork work(21);
  PipelineRunner runner(o, work.graph());
  PipelineControl control;
  auto slots = makeSlots(runner);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(runner.run(slots, control, nullptr).isOk());
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 195ms);  // 20 periods of 10 ms
  EXPECT_EQ(runner.report().published, 21);
}

TEST(PipelineRunner, StopDrainsEveryFrameInFlight) {
  PipelineOptions o;
  ScriptedWork work(1000000, 200us);
  PipelineRunner runner(o, work.graph());
  PipelineControl control;
  auto slots = makeSlots(runner);
  int ticks = 0;
  auto tick = [&] {
    if (++ticks == 5) control.stop = true;
  };
  ASSERT_TRUE(runner.run(slots, control, tick, 5).isOk());
  const PipelineReport& r = runner.report();
  EXPECT_GT(r.captured, 0);
  EXPECT_LT(r.captured, 1000000);
  EXPECT_EQ(r.published, r.captured);  // nothing captured is lost
  EXPECT_EQ(static_cast<std::int64_t>(work.published_.size()), r.captured);
}

// 100 scripted frames, threaded and sequential, where frame `at` fails (`fail`: the stage that
// fails it): the run stops with an error naming `message`, every frame before `at` published.
void expectStopsAt(int ScriptedWork::*fail, int at, const std::string& message) {
  for (bool sequential : {false, true}) {
    PipelineOptions o;
    o.sequential = sequential;
    ScriptedWork work(100);
    work.*fail = at;
    PipelineRunner runner(o, work.graph());
    PipelineControl control;
    auto slots = makeSlots(runner);
    const Status s = runner.run(slots, control, nullptr);
    EXPECT_FALSE(s.isOk());
    EXPECT_NE(s.message().find(message), std::string::npos) << s.message();
    ASSERT_EQ(work.published_.size(), static_cast<std::size_t>(at)) << "sequential " << sequential;
    EXPECT_EQ(work.published_.back().first, at - 1);
  }
}

TEST(PipelineRunner, StageErrorStopsTheRunAndIsReported) {
  expectStopsAt(&ScriptedWork::fail_at_, 40, "scripted failure");
}

TEST(PipelineRunner, CaptureErrorKeepsEveryFrameBeforeIt) {
  // Nothing already computed is lost: the frames in flight behind an unreadable frame are
  // still estimated and published.
  expectStopsAt(&ScriptedWork::capture_fail_at_, 30, "scripted unreadable frame");
}

// The graph's prepare_slot hook sizes every pooled slot once, before the first frame is read,
// in both modes.
TEST(PipelineRunner, PreparesEverySlotBeforeTheFirstFrame) {
  for (bool sequential : {false, true}) {
    ScriptedWork work(12);
    StageGraph g = work.graph();
    int prepared = 0;
    bool read_before_prepared = false;
    g.prepare_slot = [&](FrameSlot& s) {
      s.frame.right.resize(16, 8);
      ++prepared;
    };
    auto read = g.source.read;
    int needed = 0;
    g.source.read = [&prepared, &needed, &read_before_prepared, read](FrameSlot& s) {
      if (prepared < needed) read_before_prepared = true;
      EXPECT_EQ(s.frame.right.width(), 16);
      return read(s);
    };
    PipelineOptions o;
    o.sequential = sequential;
    PipelineRunner runner(o, std::move(g));
    needed = runner.slotsNeeded();
    auto slots = makeSlots(runner);
    PipelineControl control;
    ASSERT_TRUE(runner.run(slots, control, nullptr).isOk());
    EXPECT_EQ(prepared, static_cast<int>(slots.size())) << "sequential " << sequential;
    EXPECT_FALSE(read_before_prepared);
    EXPECT_EQ(work.published_.size(), 12u);
  }
}

TEST(PipelineRunner, RejectsTooFewSlotsAndBadOptions) {
  PipelineOptions o;
  ScriptedWork work(3);
  PipelineRunner runner(o, work.graph());
  PipelineControl control;
  std::vector<std::unique_ptr<FrameSlot>> slots;
  slots.push_back(std::make_unique<FrameSlot>());
  EXPECT_FALSE(runner.run(slots, control, nullptr).isOk());
  StageGraph no_stage;
  no_stage.source = work.graph().source;
  EXPECT_FALSE(no_stage.validate().isOk());
  StageGraph late_newest = work.graph();
  late_newest.stages[1].input = EdgePolicy::kNewest;  // a dropped slot could not get back
  EXPECT_FALSE(late_newest.validate().isOk());
  PipelineOptions bad;
  bad.queue_capacity = 0;
  EXPECT_FALSE(bad.validate().isOk());
  bad = PipelineOptions{};
  bad.rate_hz = -1;
  EXPECT_FALSE(bad.validate().isOk());
}

// --- svslam run: threaded == sequential, byte for byte ----------------------------------------

int runCli(const std::string& args, const fs::path& dir) {
  fs::create_directories(dir);
  return test::runSvslam("run " + args + " --out " + dir.string(), dir / "stdout.txt",
                         dir / "stderr.txt");
}

TEST(RunPipeline, ThreadedOutputsEqualSequentialOnAReplay) {
  const fs::path base = fs::temp_directory_path() / ("svslam_rt_" + std::to_string(::getpid()));
  // Small frames: this test runs under ThreadSanitizer in CI, where a frame costs ~50x more.
  const std::string src = "--source synthetic:width=320,height=240,frames=8 --max-frames 8";
  fs::create_directories(base);
  // ekf: dense stereo (the synthetic 320x240 disparities are below 40 px) and the mapper stage
  // on. vo and roi without dense stereo and mapper. roi: the stereo stage waits for the
  // estimator's feedback on the previous frame.
  const fs::path ekf_cfg = base / "ekf.yaml", vo_cfg = base / "vo.yaml",
                 roi_cfg = base / "roi.yaml";
  std::ofstream(ekf_cfg) << "dense_stereo: {max_disp_px: 48}\n";
  std::ofstream(vo_cfg) << "dense_stereo: {enabled: false}\nmap: {enabled: false}\n";
  std::ofstream(roi_cfg) << "odometry:\n  roi_tracking: true\n"
                         << "dense_stereo: {enabled: false}\nmap: {enabled: false}\n";
  for (const std::string mode : {"ekf", "vo", "roi"}) {
    const fs::path a = base / (mode + "_threaded"), b = base / (mode + "_sequential");
    const fs::path& cfg = mode == "ekf" ? ekf_cfg : mode == "vo" ? vo_cfg : roi_cfg;
    const std::string args =
        src + " --config " + cfg.string() + (mode == "roi" ? std::string() : " --mode " + mode);
    ASSERT_EQ(runCli(args, a), 0) << slurp(a / "stderr.txt");
    ASSERT_EQ(runCli(args + " --sequential", b), 0) << slurp(b / "stderr.txt");
    for (const char* f : {"trajectory_kitti.txt", "trajectory_tum.txt", "groundtruth_kitti.txt"}) {
      const std::string ta = slurp(a / f), tb = slurp(b / f);
      EXPECT_FALSE(ta.empty()) << f;
      EXPECT_EQ(ta, tb) << mode << " " << f;
    }
    if (mode != "vo") {
      EXPECT_EQ(slurp(a / "pose_covariance.txt"), slurp(b / "pose_covariance.txt"));
      EXPECT_EQ(slurp(a / "landmarks.ply"), slurp(b / "landmarks.ply"));
    }
    if (mode == "ekf") {  // the mapper stage after publication: the same map either way
      EXPECT_FALSE(slurp(a / "dem.tif").empty());
      EXPECT_EQ(slurp(a / "dem.tif"), slurp(b / "dem.tif"));
    }
    // The two runs really were threaded and sequential.
    EXPECT_NE(slurp(a / "stdout.txt").find("\"threaded\": true"), std::string::npos);
    EXPECT_NE(slurp(b / "stdout.txt").find("\"threaded\": false"), std::string::npos);
    const std::string stats = slurp(a / "stats.json");
    EXPECT_NE(stats.find("\"end_to_end\""), std::string::npos);
    EXPECT_NE(stats.find("\"frames_dropped\": 0"), std::string::npos);
  }
  fs::remove_all(base);
}

}  // namespace
}  // namespace svslam::rt

// Heap allocations per frame in steady state, counted by replacing the global operator new.
//  - The pipeline's own machinery (pooled slots, SPSC edges, stamps, latency recorders, the
//    threads' hand-offs) allocates nothing per frame: asserted.
//  - The full svslam work, counted per stage thread once warm: capture (synthetic renderer),
//    estimator (temporal matching, VME, EKF, landmark bookkeeping, stage times) and publisher
//    (output files, stats) and stereo (corners, stereo matching) allocate nothing per frame:
//    asserted, with one thread per stage and with two-thread stage pools.
// With SVSLAM_ALLOC_TRACE=1 in the environment, every allocation counted in the full-work window
// prints a backtrace on stderr (addresses: resolve with addr2line -f -C -i -e <test binary>).
#include <execinfo.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <new>

#include "drivers/source/stereo_source.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/realtime/slam_stages.hpp"
#include "pipeline/run/run_outputs.hpp"
#include "scripted_graph.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SVSLAM_COUNT_ALLOCATIONS 0  // the sanitizers own operator new: counting is skipped
#else
#define SVSLAM_COUNT_ALLOCATIONS 1
#endif

namespace {
std::atomic<std::int64_t> g_allocations{0};
// Per pipeline stage (thread_local tag set by CountingWork): 0 untagged, 1 capture, 2 stereo,
// 3 estimator, 4 publisher, 5 mapper.
std::atomic<std::int64_t> g_stage_allocations[6] = {};
thread_local int t_stage = 0;
std::atomic<bool> g_trace{false};  // SVSLAM_ALLOC_TRACE and inside the counted window
#if SVSLAM_COUNT_ALLOCATIONS
thread_local bool t_tracing = false;

// Backtrace of one allocation, written straight to stderr (no allocation of its own once
// backtrace() has been called once, which loads its unwinder).
void traceAllocation(std::size_t bytes) {
  if (!g_trace.load(std::memory_order_relaxed) || t_tracing) return;
  t_tracing = true;
  void* frames[24];
  const int n = backtrace(frames, 24);
  char head[48];
  const int len = std::snprintf(head, sizeof head, "allocation of %zu bytes:\n", bytes);
  [[maybe_unused]] const ssize_t written =
      write(STDERR_FILENO, head, static_cast<std::size_t>(len));
  backtrace_symbols_fd(frames, n, STDERR_FILENO);
  t_tracing = false;
}
#endif
}  // namespace

// The replacements below pair operator new with malloc and operator delete with free; GCC's
// -Wmismatched-new-delete cannot see that pairing once new is inlined (false positive at -O2).
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

#if SVSLAM_COUNT_ALLOCATIONS
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  g_stage_allocations[t_stage].fetch_add(1, std::memory_order_relaxed);
  traceAllocation(n);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  g_stage_allocations[t_stage].fetch_add(1, std::memory_order_relaxed);
  traceAllocation(n);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#endif

namespace svslam::rt {
namespace {

// Work that touches every slot buffer but allocates nothing once the images have their size.
class QuietWork {
 public:
  QuietWork(int frames, int first, int last) : frames_(frames), first_(first), last_(last) {}
  Result<bool> capture(FrameSlot& slot) {
    if (next_ >= frames_) return false;
    slot.frame.left.resize(64, 48);  // same size every time: no allocation once warm
    slot.frame.right.resize(64, 48);
    slot.frame.index = next_++;
    slot.frame.left.row(0)[0] = static_cast<std::uint8_t>(slot.frame.index);
    return true;
  }
  Status stereo(FrameSlot& slot) {
    slot.stereo.max_response = slot.frame.left.row(0)[0];
    return Status::ok();
  }
  Status estimate(FrameSlot& slot) {
    slot.result.landmarks_in_state = static_cast<int>(slot.stereo.max_response) + 1;
    return Status::ok();
  }
  Status publish(FrameSlot& slot) {
    sum_ += slot.result.landmarks_in_state;
    // The first frames published at or after `first_` / `last_` (the newest-frame edge may
    // drop the exact ones).
    if (slot.frame.index >= first_ && at_first_ < 0) at_first_ = g_allocations.load();
    if (slot.frame.index >= last_ && at_last_ < 0) at_last_ = g_allocations.load();
    return Status::ok();
  }
  StageGraph graph(EdgePolicy capture_input) { return fourStageGraph(*this, capture_input); }
  std::int64_t at_first_ = -1, at_last_ = -1, sum_ = 0;

 private:
  int frames_, first_, last_, next_ = 0;
};

TEST(Allocations, PipelineMachineryAllocatesNothingPerFrame) {
  if (!SVSLAM_COUNT_ALLOCATIONS)
    GTEST_SKIP() << "sanitizer build: the sanitizer's own operator new cannot be counted here";
  for (bool keep_newest : {false, true}) {
    PipelineOptions o;
    QuietWork work(600, 100, 500);
    PipelineRunner runner(o, work.graph(keep_newest ? EdgePolicy::kNewest : EdgePolicy::kBlocking));
    auto slots = makeSlots(runner);
    PipelineControl control;
    ASSERT_TRUE(runner.run(slots, control, nullptr).isOk());
    ASSERT_GE(work.at_first_, 0);
    ASSERT_GE(work.at_last_, 0);
    EXPECT_EQ(work.at_last_ - work.at_first_, 0)
        << "allocations over 400 steady-state frames (keep_newest " << keep_newest << ")";
  }
}

// Stage times: a known stage's samples go into its ring without allocating; the ring keeps the
// newest `capacity` samples for the percentiles, count and max cover every sample.
TEST(Allocations, StageTimesKeepTheNewestSamplesWithoutAllocating) {
  run::StageTimes times(4);
  times.add("ekf", 1.0);  // first sample of the stage: its ring is allocated here
  const std::int64_t before = g_allocations.load();
  for (int i = 2; i <= 10; ++i) times.add("ekf", static_cast<double>(i));
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_EQ(times.median("ekf"), 8.0);  // kept 7, 8, 9, 10: nearest rank 2 of 4
  EXPECT_NE(times.json().find("\"max_ms\": 10.000, \"count\": 10"), std::string::npos)
      << times.json();
  run::StageTimes merged(8);
  merged.add("ekf", 20.0);
  merged.merge(times);  // kept 20, 7, 8, 9, 10; 11 samples in all
  EXPECT_EQ(merged.median("ekf"), 9.0);
  EXPECT_NE(merged.json().find("\"max_ms\": 20.000, \"count\": 11"), std::string::npos)
      << merged.json();
}

// Wraps the stages of the real work, tags each stage's thread and takes the counts at two
// published frames.
class CountingWork {
 public:
  static constexpr int kStages = 6;
  // `work`, when given, is asked for the mapper's tile count.
  CountingWork(int first, int last, const SlamStages* work = nullptr)
      : first_(first), last_(last), work_(work) {}
  StageGraph wrap(StageGraph g) {
    auto read = g.source.read;
    g.source.read = [read](FrameSlot& s) {
      t_stage = 1;
      return read(s);
    };
    std::size_t sink = g.stages.size() - 1;
    if (g.stages.back().after_publish) {  // the mapper: counted over its own frames
      --sink;
      auto map = g.stages.back().work;
      g.stages.back().work = [this, map](FrameSlot& s) {
        t_stage = 5;
        const Status st = map(s);
        if (s.frame.index == first_) takeMapper(mapper_at_first_, tiles_at_first_);
        if (s.frame.index == last_) takeMapper(mapper_at_last_, tiles_at_last_);
        return st;
      };
    }
    for (std::size_t i = 0; i < sink; ++i) {
      auto work = g.stages[i].work;
      const int tag = static_cast<int>(i) + 2;
      g.stages[i].work = [work, tag](FrameSlot& s) {
        t_stage = tag;
        return work(s);
      };
    }
    auto publish = g.stages[sink].work;
    g.stages[sink].work = [this, publish](FrameSlot& s) {
      t_stage = 4;
      const Status st = publish(s);
      if (s.frame.index == first_) {
        take(at_first_);
        if (std::getenv("SVSLAM_ALLOC_TRACE")) {
          void* warm[1];
          backtrace(warm, 1);  // loads the unwinder before the window opens
          g_trace = true;
        }
      }
      if (s.frame.index == last_) {
        take(at_last_);
        g_trace = false;
      }
      return st;
    };
    return g;
  }
  std::int64_t inWindow(int stage) const { return at_last_[stage] - at_first_[stage]; }
  bool windowSeen() const { return at_first_[0] >= 0 && at_last_[0] >= 0; }
  // Mapper allocations between its frames first and last, and the tiles it created meanwhile.
  std::int64_t mapperInWindow() const { return mapper_at_last_ - mapper_at_first_; }
  int tilesCreatedInWindow() const { return tiles_at_last_ - tiles_at_first_; }
  bool mapperWindowSeen() const { return mapper_at_first_ >= 0 && mapper_at_last_ >= 0; }

 private:
  void take(std::int64_t (&at)[kStages]) {
    for (int k = 0; k < kStages; ++k) at[k] = g_stage_allocations[k].load();
  }
  void takeMapper(std::int64_t& allocations, int& tiles) {
    allocations = g_stage_allocations[5].load();
    tiles = work_ && work_->mapStage() ? work_->mapStage()->map().numTiles() : 0;
  }
  int first_, last_;
  const SlamStages* work_;
  std::int64_t at_first_[kStages] = {-1, -1, -1, -1, -1, -1};
  std::int64_t at_last_[kStages] = {-1, -1, -1, -1, -1, -1};
  std::int64_t mapper_at_first_ = -1, mapper_at_last_ = -1;
  int tiles_at_first_ = 0, tiles_at_last_ = 0;
};

// The window opens once every pooled slot has carried a frame (slotsNeeded = 11 with the default
// options; the runner sizes each slot's images and stereo output before the first frame through
// the graph's prepare_slot, which this test does not count) and the per-point scratch
// buffers have met this sequence's early frames. The EKF state needs no warm-up: P is
// preallocated for max_landmarks, landmarks are added and retired inside it, and the map's
// bookkeeping is preallocated for slam.map_reserve landmarks, far more than this run creates.
// 20 frames are counted, published frames 30 to 50. With threads = 1 each stage's work runs on
// its own thread and the per-thread counts are per stage; with threads = 2 the stage pools'
// workers count as "other threads".
class FullWork : public ::testing::TestWithParam<int> {};

TEST_P(FullWork, AllocatesNothingPerFrame) {
  if (!SVSLAM_COUNT_ALLOCATIONS)
    GTEST_SKIP() << "sanitizer build: the sanitizer's own operator new cannot be counted here";
  constexpr int kFirst = 30, kLast = 50, kFrames = 52;
  auto src = drivers::openStereoSource("synthetic:width=320,height=240,frames=52");
  ASSERT_TRUE(src.isOk()) << src.status().message();
  config::RunConfig cfg;
  cfg.threads = GetParam();
  const std::string out =
      (std::filesystem::temp_directory_path() / ("svslam_alloc_" + std::to_string(::getpid())))
          .string();
  std::filesystem::create_directories(out);
  SlamStages work(cfg, **src, out, nullptr);
  ASSERT_TRUE(work.init().isOk());
  CountingWork counting(kFirst, kLast, &work);
  PipelineOptions o;
  PipelineRunner runner(o, counting.wrap(work.graph(EdgePolicy::kBlocking)));
  ASSERT_LT(runner.slotsNeeded(), kFirst);
  auto slots = makeSlots(runner);
  PipelineControl control;
  ASSERT_TRUE(runner.run(slots, control, nullptr).isOk());
  const int frames = work.summary().frames, added = work.summary().added;
  ASSERT_TRUE(work.finish().isOk());
  std::filesystem::remove_all(out);
  ASSERT_TRUE(counting.windowSeen());
  EXPECT_EQ(frames, kFrames);
  EXPECT_GT(added, 0);  // landmarks were initialised: the filter did its full work
  const int n = kLast - kFirst;
  std::printf(
      "full svslam work (ekf, 320x240 synthetic, threads %d), heap allocations over %d "
      "frames: capture %lld, stereo %lld, estimator %lld, publisher %lld, other threads "
      "%lld\n",
      GetParam(), n, static_cast<long long>(counting.inWindow(1)),
      static_cast<long long>(counting.inWindow(2)), static_cast<long long>(counting.inWindow(3)),
      static_cast<long long>(counting.inWindow(4)), static_cast<long long>(counting.inWindow(0)));
  RecordProperty("stereo_allocations_in_window", std::to_string(counting.inWindow(2)));
  const char* where = " (SVSLAM_ALLOC_TRACE=1 prints where)";
  EXPECT_EQ(counting.inWindow(1), 0) << "capture" << where;
  EXPECT_EQ(counting.inWindow(3), 0) << "estimator" << where;
  EXPECT_EQ(counting.inWindow(4), 0) << "publisher" << where;
  EXPECT_EQ(counting.inWindow(0), 0) << "pipeline threads and stage pools" << where;
  EXPECT_EQ(counting.inWindow(2), 0) << "stereo" << where;
  // The map grows along this flight: the mapper allocates only the tiles it creates (their cells
  // and their index entry), nothing else.
  ASSERT_TRUE(counting.mapperWindowSeen());
  std::printf("mapper: %lld heap allocations over %d frames, %d tiles created\n",
              static_cast<long long>(counting.mapperInWindow()), n,
              counting.tilesCreatedInWindow());
  EXPECT_LE(counting.mapperInWindow(), 2 * counting.tilesCreatedInWindow()) << "mapper" << where;
}

INSTANTIATE_TEST_SUITE_P(Threads, FullWork, ::testing::Values(1, 2));

}  // namespace
}  // namespace svslam::rt

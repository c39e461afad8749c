// Heap allocations per frame in steady state, counted by replacing the global operator new.
//  - The pipeline's own machinery (pooled slots, SPSC edges, stamps, latency recorders, the
//    threads' hand-offs) allocates nothing per frame: asserted.
//  - The full svslam work (stereo stage, odometry, EKF, writers) is measured and printed; its
//    count is bounded loosely here (the EKF's dynamic-size algebra and the result strings still
//    allocate), see docs/pipeline.md.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <new>

#include "drivers/stereo_source.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/realtime/stage_work.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SVSLAM_COUNT_ALLOCATIONS 0  // the sanitizers own operator new: counting is skipped
#else
#define SVSLAM_COUNT_ALLOCATIONS 1
#endif

namespace {
std::atomic<std::int64_t> g_allocations{0};
}  // namespace

// The replacements below pair operator new with malloc and operator delete with free; GCC's
// -Wmismatched-new-delete cannot see that pairing once new is inlined (false positive at -O2).
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

#if SVSLAM_COUNT_ALLOCATIONS
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
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
class QuietWork : public PipelineWork {
 public:
  QuietWork(int frames, int first, int last) : frames_(frames), first_(first), last_(last) {}
  Result<bool> capture(FrameSlot& slot) override {
    if (next_ >= frames_) return false;
    slot.frame.left.resize(64, 48);  // same size every time: no allocation once warm
    slot.frame.right.resize(64, 48);
    slot.frame.index = next_++;
    slot.frame.left.row(0)[0] = static_cast<std::uint8_t>(slot.frame.index);
    return true;
  }
  Status stereo(FrameSlot& slot) override {
    slot.stereo.max_response = slot.frame.left.row(0)[0];
    return Status::ok();
  }
  Status estimate(FrameSlot& slot) override {
    slot.result.landmarks_in_state = static_cast<int>(slot.stereo.max_response) + 1;
    return Status::ok();
  }
  Status publish(FrameSlot& slot) override {
    sum_ += slot.result.landmarks_in_state;
    // The first frames published at or after `first_` / `last_` (the newest-frame edge may
    // drop the exact ones).
    if (slot.frame.index >= first_ && at_first_ < 0) at_first_ = g_allocations.load();
    if (slot.frame.index >= last_ && at_last_ < 0) at_last_ = g_allocations.load();
    return Status::ok();
  }
  std::int64_t at_first_ = -1, at_last_ = -1, sum_ = 0;

 private:
  int frames_, first_, last_, next_ = 0;
};

TEST(Allocations, PipelineMachineryAllocatesNothingPerFrame) {
  if (!SVSLAM_COUNT_ALLOCATIONS)
    GTEST_SKIP() << "sanitizer build: the sanitizer's own operator new cannot be counted here";
  for (bool keep_newest : {false, true}) {
    PipelineOptions o;
    o.keep_newest = keep_newest;
    QuietWork work(600, 100, 500);
    std::vector<std::unique_ptr<FrameSlot>> slots;
    for (int i = 0; i < PipelineRunner::slotsNeeded(o); ++i)
      slots.push_back(std::make_unique<FrameSlot>());
    PipelineRunner runner(o, work);
    PipelineControl control;
    ASSERT_TRUE(runner.run(slots, control, nullptr).isOk());
    ASSERT_GE(work.at_first_, 0);
    ASSERT_GE(work.at_last_, 0);
    EXPECT_EQ(work.at_last_ - work.at_first_, 0)
        << "allocations over 400 steady-state frames (keep_newest " << keep_newest << ")";
  }
}

// Wraps the real work and counts allocations between two published frames.
class CountingWork : public PipelineWork {
 public:
  CountingWork(RunWork& w, int first, int last) : w_(w), first_(first), last_(last) {}
  Result<bool> capture(FrameSlot& s) override { return w_.capture(s); }
  Status stereo(FrameSlot& s) override { return w_.stereo(s); }
  Status estimate(FrameSlot& s) override { return w_.estimate(s); }
  Status publish(FrameSlot& s) override {
    const Status st = w_.publish(s);
    if (s.frame.index == first_) at_first_ = g_allocations.load();
    if (s.frame.index == last_) at_last_ = g_allocations.load();
    return st;
  }
  std::int64_t at_first_ = -1, at_last_ = -1;

 private:
  RunWork& w_;
  int first_, last_;
};

TEST(Allocations, FullWorkPerFrameIsMeasured) {
  if (!SVSLAM_COUNT_ALLOCATIONS)
    GTEST_SKIP() << "sanitizer build: the sanitizer's own operator new cannot be counted here";
  auto src = io::openStereoSource("synthetic:width=320,height=240,frames=16");
  ASSERT_TRUE(src.isOk()) << src.status().message();
  config::RunConfig cfg;
  const std::string out = (std::filesystem::temp_directory_path() /
                           ("svslam_alloc_" + std::to_string(::getpid())))
                              .string();
  std::filesystem::create_directories(out);
  RunWork work(cfg, **src, out, nullptr);
  ASSERT_TRUE(work.init().isOk());
  CountingWork counting(work, 5, 15);
  PipelineOptions o;
  std::vector<std::unique_ptr<FrameSlot>> slots;
  for (int i = 0; i < PipelineRunner::slotsNeeded(o); ++i)
    slots.push_back(std::make_unique<FrameSlot>());
  PipelineRunner runner(o, counting);
  PipelineControl control;
  ASSERT_TRUE(runner.run(slots, control, nullptr).isOk());
  ASSERT_TRUE(work.finish().isOk());
  std::filesystem::remove_all(out);
  const double per_frame = static_cast<double>(counting.at_last_ - counting.at_first_) / 10.0;
  std::printf("full svslam work (ekf, 320x240 synthetic): %.1f heap allocations per frame\n",
              per_frame);
  RecordProperty("allocations_per_frame", std::to_string(per_frame));
  EXPECT_GE(per_frame, 0.0);
  EXPECT_LT(per_frame, 20000.0);  // loose: catches a runaway (e.g. per-pixel allocation)
}

}  // namespace
}  // namespace svslam::rt

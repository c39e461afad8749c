#pragma once
// The real-time pipeline: one thread per stage,
//   capture -> stereo -> estimator -> publisher
// connected by bounded lock-free SPSC edges (realtime/edges.hpp) that carry pointers to pooled
// frame slots; the publisher returns each slot to capture through a free-slot ring.
//  - capture -> stereo: NewestEdge (keep the newest, count every drop) for cameras and paced
//    replays (options.keep_newest), else BlockingEdge (back-pressure, no drop);
//  - stereo -> estimator -> publisher: BlockingEdge of options.queue_capacity.
// The estimator stage holds the temporal matching, the VME and the EKF: the VME of frame k uses
// the non-landmark matches, which depend on the EKF's landmarks of frame k-1, and the temporal
// search of frame k is predicted with the motion of frame k-1, so these steps form one chain per
// frame and run on one thread; the stereo stage (dense stereo, detection, stereo matching) has
// no frame-to-frame state and runs ahead on its own thread.
// options.sequential runs the same work on the calling thread, one frame after the other: the
// outputs are the same byte for byte (nothing drops in either mode without keep_newest).
// Stop: PipelineControl::stop (signal, command, error) stops capture; the frames in flight are
// drained through every stage, then run() returns.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "pipeline/realtime/frame_slot.hpp"
#include "pipeline/realtime/latency_stats.hpp"

namespace svslam::rt {

// The work of each stage, independent of threading. Each method is called from one thread only
// (its stage's), on a slot no other stage holds at that time.
class PipelineWork {
 public:
  virtual ~PipelineWork() = default;
  // Reads the next pair into `slot` (frame, seq, ground truth); false at the end of the stream.
  virtual Result<bool> capture(FrameSlot& slot) = 0;
  virtual Status stereo(FrameSlot& slot) = 0;
  virtual Status estimate(FrameSlot& slot) = 0;
  // Writes / sends the pose of a slot whose stages all succeeded.
  virtual Status publish(FrameSlot& slot) = 0;
  // Called on the stage's own thread before its first frame (thread name, affinity, priority).
  virtual void onThreadStart(const char* stage) { (void)stage; }
};

struct PipelineOptions {
  bool sequential = false;   // run every stage on the calling thread
  double rate_hz = 0.0;      // pace capture at this rate (replays); 0 = as fast as possible
  bool keep_newest = false;  // capture edge keeps the newest frame and counts drops
  int queue_capacity = 2;    // slots per blocking edge, >= 1
  Status validate() const;
};

// Shared between the pipeline and whoever controls it (signal handler flag, LCM commands).
struct PipelineControl {
  std::atomic<bool> stop{false};
  std::atomic<bool> pause{false};
};

struct EdgeReport {
  std::string name;
  int capacity = 0, max_depth = 0, depth = 0;
  std::int64_t drops = 0;
};

struct PipelineReport {
  std::int64_t captured = 0, published = 0, dropped = 0, failed = 0;
  Status error;  // first stage error (the run stopped there)
  LatencySummary capture, stereo, estimate, publish;  // stage durations
  LatencySummary end_to_end;                          // capture instant -> pose published
  std::vector<EdgeReport> edges;
  double wall_s = 0.0;
  double fps = 0.0;  // published / wall time
};

class PipelineRunner {
 public:
  PipelineRunner(const PipelineOptions& options, PipelineWork& work);
  ~PipelineRunner();
  // Slots the pool needs for the options (threaded: every edge full plus one per stage).
  static int slotsNeeded(const PipelineOptions& options);
  // Runs until the end of the stream, a stage error or control.stop. `slots` (slotsNeeded of
  // them, preallocated by the caller) are the whole frame memory. `tick` is called about every
  // tick_ms (threaded: from the calling thread while the stages run; sequential: between frames)
  // for the control loop: commands, watchdog, progress.
  Status run(std::vector<std::unique_ptr<FrameSlot>>& slots, PipelineControl& control,
             const std::function<void()>& tick, int tick_ms = 100);
  // Progress, readable from any thread while run() runs.
  std::int64_t published() const { return published_.load(std::memory_order_relaxed); }
  std::int64_t captured() const { return captured_.load(std::memory_order_relaxed); }
  // After run().
  const PipelineReport& report() const { return report_; }

 private:
  struct Impl;
  Status runSequential(std::vector<std::unique_ptr<FrameSlot>>& slots, PipelineControl& control,
                       const std::function<void()>& tick);
  Status runThreaded(std::vector<std::unique_ptr<FrameSlot>>& slots, PipelineControl& control,
                     const std::function<void()>& tick, int tick_ms);

  PipelineOptions options_;
  PipelineWork& work_;
  std::atomic<std::int64_t> published_{0}, captured_{0};
  PipelineReport report_;
};

// Steady clock, ns.
std::int64_t steadyNowNs();

}  // namespace svslam::rt

#pragma once
// The real-time pipeline: runs a StageGraph (realtime/stage_graph.hpp) with one thread per
// stage, connected by bounded lock-free SPSC edges (realtime/edges.hpp) that carry pointers to
// pooled frame slots; after the last stage each slot returns to the source through a free-slot
// ring. options.sequential runs the same graph on the calling thread, one frame after the
// other: the outputs are the same byte for byte (nothing drops in either mode without a
// kNewest edge). Both modes share the capture (pacing, pause, stamps) and the timing: every
// stage's duration and the end-to-end latency (capture instant -> sink done) are recorded from
// the slot's stamps once the sink is done, on the sink's thread.
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
#include "pipeline/realtime/pipeline_options.hpp"
#include "pipeline/realtime/stage_graph.hpp"
#include "pipeline/realtime/stage_health.hpp"

namespace svslam::rt {

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

struct StageReport {
  std::string name;
  LatencySummary latency;  // the stage's work per frame
};

// Per-stage and end-to-end latency recorders, written on the sink's thread only.
class StageTimings {
 public:
  explicit StageTimings(const StageGraph& graph);
  // Records a frame the sink has finished.
  void record(const FrameSlot& slot);
  // index 0: the source; 1..n: stages[0..n-1].
  const std::vector<std::string>& names() const { return names_; }
  const LatencyRecorder& stage(std::size_t index) const { return per_stage_[index]; }
  const LatencyRecorder& endToEnd() const { return e2e_; }
  void clear();

 private:
  std::vector<std::string> names_;
  std::vector<LatencyRecorder> per_stage_;
  LatencyRecorder e2e_;
};

struct PipelineReport {
  std::int64_t captured = 0, published = 0, dropped = 0, failed = 0;
  // Published frames the stage after publication (StageSpec::after_publish) skipped because it
  // was still busy with an earlier one.
  std::int64_t after_publish_skipped = 0;
  Status error;                     // first stage error (the run stopped there)
  std::vector<StageReport> stages;  // the source, then each stage, in order
  LatencySummary end_to_end;        // capture instant -> pose published
  std::vector<EdgeReport> edges;
  double wall_s = 0.0;
  double fps = 0.0;  // published / wall time
  // Stalls (realtime/stage_health.hpp) with the threshold of the run (0: not counted).
  HealthSnapshot health;
  std::int64_t stall_threshold_ns = 0;
  // The stage called `name` (an empty summary when there is none).
  LatencySummary stage(const std::string& name) const;
};

class PipelineRunner {
 public:
  PipelineRunner(const PipelineOptions& options, StageGraph graph);
  ~PipelineRunner();
  // Slots the pool needs (threaded: every edge full plus one per stage and a spare).
  static int slotsNeeded(const PipelineOptions& options, const StageGraph& graph);
  int slotsNeeded() const { return slotsNeeded(options_, graph_); }
  // Runs until the end of the stream, a stage error or control.stop. `slots` (slotsNeeded of
  // them, preallocated by the caller) are the whole frame memory. `tick` is called about every
  // tick_ms (threaded: from the calling thread while the stages run; sequential: between frames)
  // for the control loop: commands, watchdog, progress.
  Status run(std::vector<std::unique_ptr<FrameSlot>>& slots, PipelineControl& control,
             const std::function<void()>& tick, int tick_ms = 100);
  // Progress, readable from any thread while run() runs.
  std::int64_t published() const { return published_.load(std::memory_order_relaxed); }
  std::int64_t captured() const { return captured_.load(std::memory_order_relaxed); }
  // The latencies so far: read from the sink stage's work (its thread) or after run().
  const StageTimings& timings() const { return timings_; }
  // Per-stage health (the source, then every stage): snapshot() from any thread while run()
  // runs. A stage's frame that takes longer than `ns` counts as a stall (<= 0: none does); set
  // before run().
  const StageHealth& health() const { return health_; }
  void setStallThresholdNs(std::int64_t ns) { health_.setStallThresholdNs(ns); }
  // After run().
  const PipelineReport& report() const { return report_; }

 private:
  class Capture;
  Status runSequential(std::vector<std::unique_ptr<FrameSlot>>& slots, PipelineControl& control,
                       const std::function<void()>& tick);
  Status runThreaded(std::vector<std::unique_ptr<FrameSlot>>& slots, PipelineControl& control,
                     const std::function<void()>& tick, int tick_ms);
  void finishReport();
  // Stages up to and including the sink (all but a stage after publication).
  std::size_t numMainStages() const {
    return graph_.stages.size() - (graph_.stages.back().after_publish ? 1 : 0);
  }

  PipelineOptions options_;
  StageGraph graph_;
  StageTimings timings_;
  StageHealth health_;
  std::atomic<std::int64_t> published_{0}, captured_{0};
  PipelineReport report_;
};

// Steady clock, ns.
std::int64_t steadyNowNs();

}  // namespace svslam::rt

#include "pipeline/realtime/pipeline_runner.hpp"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <thread>

#include "pipeline/realtime/edges.hpp"

namespace svslam::rt {

using std::chrono::microseconds;
using std::chrono::milliseconds;

std::int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

namespace {

constexpr microseconds kPollTimeout{50000};  // how often a waiting stage re-checks for stop

// Sleeps until `due_ns` (steady clock) in short steps, returning early on stop.
void sleepUntil(std::int64_t due_ns, const PipelineControl& control) {
  for (;;) {
    const std::int64_t left = due_ns - steadyNowNs();
    if (left <= 0 || control.stop.load(std::memory_order_relaxed)) return;
    std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<std::int64_t>(left, 20000000)));
  }
}

// The edge into a stage: a blocking FIFO or a newest-frame mailbox.
class StageEdge {
 public:
  StageEdge(EdgePolicy policy, int capacity) {
    if (policy == EdgePolicy::kNewest)
      newest_ = std::make_unique<NewestEdge<FrameSlot>>();
    else
      fifo_ = std::make_unique<BlockingEdge<FrameSlot>>(static_cast<std::size_t>(capacity));
  }
  // Returns the slot the push displaced (kNewest), else nullptr.
  FrameSlot* push(FrameSlot* slot) {
    if (newest_) return newest_->push(slot);
    fifo_->push(slot);
    return nullptr;
  }
  bool pop(FrameSlot*& out) {
    return newest_ ? newest_->pop(out, kPollTimeout) : fifo_->pop(out, kPollTimeout);
  }
  void close() { newest_ ? newest_->close() : fifo_->close(); }
  EdgeReport report(const std::string& name) const {
    if (newest_) return {name, newest_->capacity(), newest_->maxDepth(), 0, newest_->drops()};
    return {name, fifo_->capacity(), fifo_->maxDepth(), 0, 0};
  }

 private:
  std::unique_ptr<NewestEdge<FrameSlot>> newest_;
  std::unique_ptr<BlockingEdge<FrameSlot>> fifo_;
};

}  // namespace

// Capture, shared by both modes: pause, replay pacing (frame k is due at start + k / rate,
// shifted by the time spent paused), the source's read, stamps and sequence numbers.
class PipelineRunner::Capture {
 public:
  Capture(const SourceSpec& source, double rate_hz, PipelineControl& control,
          std::atomic<std::int64_t>& captured, StageHealth& health)
      : source_(source),
        period_ns_(rate_hz > 0 ? static_cast<std::int64_t>(1e9 / rate_hz) : 0),
        control_(control),
        captured_(captured),
        health_(health) {}
  // True while paused (after a short sleep): the caller loops back to its stop check.
  bool paused() {
    if (!control_.pause.load()) return false;
    const std::int64_t p0 = steadyNowNs();
    std::this_thread::sleep_for(milliseconds(10));
    paused_ns_ += steadyNowNs() - p0;
    return true;
  }
  // The next frame into `slot`; false at the end of the stream or on stop.
  Result<bool> read(FrameSlot& slot) {
    std::int64_t start = steadyNowNs();
    if (period_ns_ > 0) {
      if (start_ns_ < 0) start_ns_ = start;
      const std::int64_t due = start_ns_ + k_ * period_ns_ + paused_ns_;
      sleepUntil(due, control_);
      start = due;
    }
    if (control_.stop.load()) return false;
    slot.stamps = FrameStamps{};
    slot.stamps.capture_ns = start;
    slot.stamps.read_start_ns = steadyNowNs();
    Result<bool> more = false;
    {
      StageWork busy(health_, 0);
      more = source_.read(slot);
    }
    if (!more || !*more) return more;
    slot.stamps.captured_ns = steadyNowNs();
    if (period_ns_ <= 0) slot.stamps.capture_ns = slot.stamps.captured_ns;
    slot.seq = k_++;
    slot.failed = false;
    captured_.fetch_add(1, std::memory_order_relaxed);
    return true;
  }

 private:
  const SourceSpec& source_;
  std::int64_t period_ns_;
  PipelineControl& control_;
  std::atomic<std::int64_t>& captured_;
  StageHealth& health_;
  std::int64_t start_ns_ = -1, paused_ns_ = 0, k_ = 0;
};

Status StageGraph::validate() const {
  if (!source.read) return Status::invalidArgument("pipeline: the source has no read function");
  if (stages.empty() || static_cast<int>(stages.size()) > FrameStamps::kMaxStages)
    return Status::invalidArgument("pipeline: 1 to " + std::to_string(FrameStamps::kMaxStages) +
                                   " stages after the source");
  for (std::size_t i = 0; i < stages.size(); ++i) {
    if (!stages[i].work)
      return Status::invalidArgument("pipeline: stage '" + stages[i].name +
                                     "' has no work function");
    const bool last = i + 1 == stages.size();
    if (stages[i].after_publish && (!last || i == 0))
      return Status::invalidArgument(
          "pipeline: stage '" + stages[i].name +
          "': only the last stage, after another, runs after publication");
    // A displaced slot goes back to the source: only the source (or the sink, for a stage after
    // publication) can take it.
    if (i > 0 && stages[i].input == EdgePolicy::kNewest && !stages[i].after_publish)
      return Status::invalidArgument("pipeline: stage '" + stages[i].name +
                                     "': only the first stage's input may keep the newest frame");
  }
  return Status::ok();
}

Status PipelineOptions::validate() const {
  if (!(rate_hz >= 0.0 && rate_hz <= 10000.0))
    return Status::invalidArgument("pipeline: rate_hz must be in [0, 10000]");
  if (queue_capacity < 1 || queue_capacity > 64)
    return Status::invalidArgument("pipeline: queue_capacity must be in [1, 64]");
  return Status::ok();
}

StageTimings::StageTimings(const StageGraph& graph) {
  names_.push_back(graph.source.name);
  for (const StageSpec& s : graph.stages)
    if (!s.after_publish) names_.push_back(s.name);
  per_stage_.resize(names_.size());
}

void StageTimings::record(const FrameSlot& slot) {
  const FrameStamps& st = slot.stamps;
  per_stage_[0].add(st.captured_ns - st.read_start_ns);
  for (std::size_t i = 1; i < per_stage_.size(); ++i)
    per_stage_[i].add(st.end_ns[i - 1] - st.start_ns[i - 1]);
  e2e_.add(st.end_ns[per_stage_.size() - 2] - st.capture_ns);
}

void StageTimings::clear() {
  for (LatencyRecorder& r : per_stage_) r.clear();
  e2e_.clear();
}

LatencySummary PipelineReport::stage(const std::string& name) const {
  for (const StageReport& s : stages)
    if (s.name == name) return s.latency;
  return LatencySummary{};
}

namespace {
// The source, then every stage (the one after publication too).
std::vector<std::string> stageNames(const StageGraph& g) {
  std::vector<std::string> names{g.source.name};
  for (const StageSpec& s : g.stages) names.push_back(s.name);
  return names;
}
}  // namespace

PipelineRunner::PipelineRunner(const PipelineOptions& options, StageGraph graph)
    : options_(options), graph_(std::move(graph)), timings_(graph_), health_(stageNames(graph_)) {}

PipelineRunner::~PipelineRunner() = default;

int PipelineRunner::slotsNeeded(const PipelineOptions& o, const StageGraph& g) {
  if (o.sequential) return 1;
  // One held by the source and by each stage, every edge full, and one spare so capture
  // rarely waits for a free slot.
  int n = 1 + static_cast<int>(g.stages.size()) + 1;
  for (const StageSpec& s : g.stages) n += s.input == EdgePolicy::kNewest ? 1 : o.queue_capacity;
  return n;
}

Status PipelineRunner::run(std::vector<std::unique_ptr<FrameSlot>>& slots, PipelineControl& control,
                           const std::function<void()>& tick, int tick_ms) {
  if (Status s = options_.validate(); !s) return s;
  if (Status s = graph_.validate(); !s) return s;
  if (static_cast<int>(slots.size()) < slotsNeeded())
    return Status::invalidArgument("pipeline: " + std::to_string(slots.size()) +
                                   " frame slots, needs " + std::to_string(slotsNeeded()));
  if (graph_.prepare_slot)
    for (auto& slot : slots) graph_.prepare_slot(*slot);
  report_ = PipelineReport{};
  timings_.clear();
  health_.reset();
  published_ = 0;
  captured_ = 0;
  const std::int64_t t0 = steadyNowNs();
  Status s = options_.sequential ? runSequential(slots, control, tick)
                                 : runThreaded(slots, control, tick, std::max(tick_ms, 1));
  report_.error = s;
  report_.wall_s = static_cast<double>(steadyNowNs() - t0) * 1e-9;
  finishReport();
  return s;
}

void PipelineRunner::finishReport() {
  report_.captured = captured_;
  report_.published = published_;
  report_.fps = report_.wall_s > 0 ? static_cast<double>(report_.published) / report_.wall_s : 0;
  const std::vector<std::string>& names = timings_.names();
  for (std::size_t i = 0; i < names.size(); ++i)
    report_.stages.push_back({names[i], timings_.stage(i).summary()});
  report_.end_to_end = timings_.endToEnd().summary();
  report_.health = health_.snapshot(steadyNowNs());
  report_.stall_threshold_ns = health_.stallThresholdNs();
  for (std::size_t i = 0; i < report_.edges.size(); ++i) {
    if (i < graph_.stages.size() && graph_.stages[i].after_publish)
      report_.after_publish_skipped += report_.edges[i].drops;  // published, not processed
    else
      report_.dropped += report_.edges[i].drops;
  }
}

Status PipelineRunner::runSequential(std::vector<std::unique_ptr<FrameSlot>>& slots,
                                     PipelineControl& control, const std::function<void()>& tick) {
  FrameSlot& slot = *slots.front();
  Capture capture(graph_.source, options_.rate_hz, control, captured_, health_);
  if (graph_.on_thread_start) graph_.on_thread_start("pipeline");
  Status error;
  while (!control.stop.load() && error) {
    if (tick) tick();
    if (capture.paused()) continue;
    auto more = capture.read(slot);
    if (!more) {
      error = more.status();
      break;
    }
    if (!*more) break;
    const std::size_t n_main = numMainStages();
    for (std::size_t i = 0; i < n_main && error; ++i) {
      StageWork busy(health_, i + 1);
      slot.stamps.start_ns[i] = steadyNowNs();
      error = graph_.stages[i].work(slot);
      slot.stamps.end_ns[i] = steadyNowNs();
    }
    if (!error) break;
    timings_.record(slot);
    published_.fetch_add(1, std::memory_order_relaxed);
    if (n_main < graph_.stages.size()) {  // the stage after publication, on every frame
      StageWork busy(health_, n_main + 1);
      slot.stamps.start_ns[n_main] = steadyNowNs();
      error = graph_.stages[n_main].work(slot);
      slot.stamps.end_ns[n_main] = steadyNowNs();
      if (!error) break;
    }
  }
  if (tick) tick();
  return error;
}

Status PipelineRunner::runThreaded(std::vector<std::unique_ptr<FrameSlot>>& slots,
                                   PipelineControl& control, const std::function<void()>& tick,
                                   int tick_ms) {
  const std::size_t n = graph_.stages.size();
  const std::size_t n_main = numMainStages();
  BlockingEdge<FrameSlot> free_slots(slots.size() + 1);
  // With a stage after publication, the sink hands slots back through its own ring (each ring
  // has a single producer): those the side stage's newest-frame edge displaced, and failed ones.
  BlockingEdge<FrameSlot> sink_returns(slots.size() + 1);
  const bool side = n_main < n;
  for (auto& s : slots) free_slots.push(s.get());
  std::vector<std::unique_ptr<StageEdge>> edges;  // edges[i]: into stages[i]
  for (const StageSpec& s : graph_.stages)
    edges.push_back(std::make_unique<StageEdge>(s.input, options_.queue_capacity));
  std::mutex error_mutex;
  Status first_error;
  std::atomic<std::int64_t> failed{0};
  std::atomic<int> running{static_cast<int>(n) + 1};
  auto fail = [&](const Status& s) {
    std::lock_guard<std::mutex> lock(error_mutex);
    if (first_error) first_error = s;
    control.stop = true;
  };
  auto threadStart = [&](const std::string& name) {
    if (graph_.on_thread_start) graph_.on_thread_start(name);
  };

  std::vector<std::thread> threads;
  threads.emplace_back([&] {
    threadStart(graph_.source.name);
    Capture capture(graph_.source, options_.rate_hz, control, captured_, health_);
    std::vector<FrameSlot*> stash;  // slots handed back by a newest-frame edge
    stash.reserve(2);
    while (!control.stop.load()) {
      if (capture.paused()) continue;
      FrameSlot* slot = nullptr;
      if (!stash.empty()) {
        slot = stash.back();
        stash.pop_back();
      }
      while (!slot && !control.stop.load()) {
        if (side && sink_returns.pop(slot, microseconds(0)) && slot) break;
        (void)free_slots.pop(slot, side ? microseconds(1000) : kPollTimeout);
      }
      if (!slot) break;
      auto more = capture.read(*slot);
      if (!more || !*more) {
        if (!more) fail(more.status());
        break;  // the slot stays out of the pool: the run is over
      }
      if (FrameSlot* old = edges[0]->push(slot)) stash.push_back(old);
    }
    edges[0]->close();
    running.fetch_sub(1);
  });

  // Stage i: takes slots from edges[i] until closed, runs its work on those not failed, forwards
  // every slot to edges[i + 1] (the sink: records and counts it, then returns it to the pool).
  // Frames ahead of a failure (already past this stage) are still published; after this stage
  // fails, every later frame is skipped here and downstream.
  for (std::size_t i = 0; i < n; ++i) {
    threads.emplace_back([&, i] {
      const StageSpec& stage = graph_.stages[i];
      const bool sink = i + 1 == n_main;
      const bool after_publish = i >= n_main;
      threadStart(stage.name);
      bool this_stage_failed = false;
      for (;;) {
        FrameSlot* slot = nullptr;
        if (!edges[i]->pop(slot)) continue;
        if (!slot) break;
        if (this_stage_failed) slot->failed = true;
        if (!slot->failed) {
          Status s;
          {
            StageWork busy(health_, i + 1);
            slot->stamps.start_ns[i] = steadyNowNs();
            s = stage.work(*slot);
            slot->stamps.end_ns[i] = steadyNowNs();
          }
          if (!s) {
            slot->failed = true;
            this_stage_failed = true;
            fail(s);
          }
        }
        if (after_publish) {
          free_slots.push(slot);
          continue;
        }
        if (!sink) {
          edges[i + 1]->push(slot);
          continue;
        }
        if (slot->failed) {
          failed.fetch_add(1);
        } else {
          timings_.record(*slot);
          published_.fetch_add(1, std::memory_order_relaxed);
        }
        if (!side) {
          free_slots.push(slot);
        } else if (slot->failed) {
          sink_returns.push(slot);
        } else if (FrameSlot* skipped = edges[i + 1]->push(slot)) {
          sink_returns.push(skipped);
        }
      }
      if (!after_publish && (!sink || side)) edges[i + 1]->close();
      running.fetch_sub(1);
    });
  }

  std::int64_t next_tick = steadyNowNs();
  while (running.load() > 0) {
    if (tick && steadyNowNs() >= next_tick) {
      tick();
      next_tick = steadyNowNs() + static_cast<std::int64_t>(tick_ms) * 1000000;
    }
    std::this_thread::sleep_for(milliseconds(std::min(tick_ms, 10)));
  }
  for (std::thread& t : threads) t.join();
  if (tick) tick();
  report_.failed = failed.load();
  std::string from = graph_.source.name;
  for (std::size_t i = 0; i < n; ++i) {
    report_.edges.push_back(edges[i]->report(from + "->" + graph_.stages[i].name));
    from = graph_.stages[i].name;
  }
  return first_error;
}

}  // namespace svslam::rt

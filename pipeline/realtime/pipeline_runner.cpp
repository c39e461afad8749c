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

// Replay pacing: frame k is due at start + k / rate, shifted by the time spent paused.
class Pacer {
 public:
  explicit Pacer(double rate_hz)
      : period_ns_(rate_hz > 0 ? static_cast<std::int64_t>(1e9 / rate_hz) : 0) {}
  bool active() const { return period_ns_ > 0; }
  std::int64_t due(std::int64_t k) {
    if (start_ns_ < 0) start_ns_ = steadyNowNs();
    return start_ns_ + k * period_ns_ + paused_ns_;
  }
  void paused(std::int64_t ns) { paused_ns_ += ns; }

 private:
  std::int64_t period_ns_;
  std::int64_t start_ns_ = -1;
  std::int64_t paused_ns_ = 0;
};

}  // namespace

Status PipelineOptions::validate() const {
  if (!(rate_hz >= 0.0 && rate_hz <= 10000.0))
    return Status::invalidArgument("pipeline: rate_hz must be in [0, 10000]");
  if (queue_capacity < 1 || queue_capacity > 64)
    return Status::invalidArgument("pipeline: queue_capacity must be in [1, 64]");
  return Status::ok();
}

PipelineRunner::PipelineRunner(const PipelineOptions& options, PipelineWork& work)
    : options_(options), work_(work) {}

PipelineRunner::~PipelineRunner() = default;

int PipelineRunner::slotsNeeded(const PipelineOptions& o) {
  if (o.sequential) return 1;
  // One held by each of the four stages, the capture edge (1 for the mailbox, else its
  // capacity), the two blocking edges, and one spare so capture rarely waits for a free slot.
  const int capture_edge = o.keep_newest ? 1 : o.queue_capacity;
  return 4 + capture_edge + 2 * o.queue_capacity + 1;
}

Status PipelineRunner::run(std::vector<std::unique_ptr<FrameSlot>>& slots,
                           PipelineControl& control, const std::function<void()>& tick,
                           int tick_ms) {
  if (Status s = options_.validate(); !s) return s;
  if (static_cast<int>(slots.size()) < slotsNeeded(options_))
    return Status::invalidArgument("pipeline: " + std::to_string(slots.size()) +
                                   " frame slots, needs " +
                                   std::to_string(slotsNeeded(options_)));
  report_ = PipelineReport{};
  published_ = 0;
  captured_ = 0;
  const std::int64_t t0 = steadyNowNs();
  Status s = options_.sequential ? runSequential(slots, control, tick)
                                 : runThreaded(slots, control, tick, std::max(tick_ms, 1));
  report_.wall_s = static_cast<double>(steadyNowNs() - t0) * 1e-9;
  report_.captured = captured_;
  report_.published = published_;
  report_.fps = report_.wall_s > 0 ? static_cast<double>(report_.published) / report_.wall_s : 0;
  return s;
}

Status PipelineRunner::runSequential(std::vector<std::unique_ptr<FrameSlot>>& slots,
                                     PipelineControl& control,
                                     const std::function<void()>& tick) {
  LatencyRecorder rec_capture, rec_stereo, rec_estimate, rec_publish, rec_e2e;
  FrameSlot& slot = *slots.front();
  Pacer pacer(options_.rate_hz);
  std::int64_t k = 0;
  Status error;
  work_.onThreadStart("pipeline");
  while (!control.stop.load()) {
    if (tick) tick();
    if (control.pause.load()) {
      const std::int64_t p0 = steadyNowNs();
      std::this_thread::sleep_for(milliseconds(10));
      pacer.paused(steadyNowNs() - p0);
      continue;
    }
    std::int64_t start = steadyNowNs();
    if (pacer.active()) {
      const std::int64_t due = pacer.due(k);
      sleepUntil(due, control);
      if (control.stop.load()) break;
      start = due;
    }
    slot.stamps = FrameStamps{};
    slot.stamps.capture_ns = start;
    const std::int64_t c0 = steadyNowNs();
    auto more = work_.capture(slot);
    if (!more) {
      error = more.status();
      break;
    }
    if (!*more) break;
    slot.stamps.captured_ns = steadyNowNs();
    if (!pacer.active()) slot.stamps.capture_ns = slot.stamps.captured_ns;
    rec_capture.add(slot.stamps.captured_ns - c0);
    slot.seq = k++;
    slot.failed = false;
    captured_.fetch_add(1, std::memory_order_relaxed);
    auto timed = [&](std::int64_t& a, std::int64_t& b, LatencyRecorder& rec, auto&& fn) {
      a = steadyNowNs();
      Status st = fn();
      b = steadyNowNs();
      rec.add(b - a);
      return st;
    };
    FrameStamps& st = slot.stamps;
    if (Status e = timed(st.stereo_start_ns, st.stereo_end_ns, rec_stereo,
                         [&] { return work_.stereo(slot); });
        !e) {
      error = e;
      break;
    }
    if (Status e = timed(st.estimate_start_ns, st.estimate_end_ns, rec_estimate,
                         [&] { return work_.estimate(slot); });
        !e) {
      error = e;
      break;
    }
    if (Status e = timed(st.publish_start_ns, st.published_ns, rec_publish,
                         [&] { return work_.publish(slot); });
        !e) {
      error = e;
      break;
    }
    rec_e2e.add(st.published_ns - st.capture_ns);
    published_.fetch_add(1, std::memory_order_relaxed);
  }
  if (tick) tick();
  report_.error = error;
  report_.capture = rec_capture.summary();
  report_.stereo = rec_stereo.summary();
  report_.estimate = rec_estimate.summary();
  report_.publish = rec_publish.summary();
  report_.end_to_end = rec_e2e.summary();
  return error;
}

Status PipelineRunner::runThreaded(std::vector<std::unique_ptr<FrameSlot>>& slots,
                                   PipelineControl& control, const std::function<void()>& tick,
                                   int tick_ms) {
  const int qcap = options_.queue_capacity;
  BlockingEdge<FrameSlot> free_slots(slots.size() + 1);
  for (auto& s : slots) free_slots.push(s.get());
  NewestEdge<FrameSlot> capture_newest;
  BlockingEdge<FrameSlot> capture_fifo(static_cast<std::size_t>(qcap));
  BlockingEdge<FrameSlot> to_estimator(static_cast<std::size_t>(qcap));
  BlockingEdge<FrameSlot> to_publisher(static_cast<std::size_t>(qcap));
  LatencyRecorder rec_capture, rec_stereo, rec_estimate, rec_publish, rec_e2e;
  std::mutex error_mutex;
  Status first_error;
  std::atomic<std::int64_t> failed{0};
  std::atomic<int> running{4};
  auto fail = [&](const Status& s) {
    std::lock_guard<std::mutex> lock(error_mutex);
    if (first_error) first_error = s;
    control.stop = true;
  };

  std::thread capture([&] {
    work_.onThreadStart("capture");
    std::vector<FrameSlot*> stash;  // slots handed back by the newest-frame edge
    stash.reserve(2);
    Pacer pacer(options_.rate_hz);
    std::int64_t k = 0;
    while (!control.stop.load()) {
      if (control.pause.load()) {
        const std::int64_t p0 = steadyNowNs();
        std::this_thread::sleep_for(milliseconds(10));
        pacer.paused(steadyNowNs() - p0);
        continue;
      }
      FrameSlot* slot = nullptr;
      if (!stash.empty()) {
        slot = stash.back();
        stash.pop_back();
      }
      while (!slot && !control.stop.load()) (void)free_slots.pop(slot, kPollTimeout);
      if (!slot) break;
      std::int64_t start = steadyNowNs();
      if (pacer.active()) {
        const std::int64_t due = pacer.due(k);
        sleepUntil(due, control);
        start = due;
      }
      if (control.stop.load()) {
        stash.push_back(slot);
        break;
      }
      slot->stamps = FrameStamps{};
      slot->stamps.capture_ns = start;
      const std::int64_t c0 = steadyNowNs();
      auto more = work_.capture(*slot);
      if (!more || !*more) {
        if (!more) fail(more.status());
        stash.push_back(slot);
        break;
      }
      slot->stamps.captured_ns = steadyNowNs();
      if (!pacer.active()) slot->stamps.capture_ns = slot->stamps.captured_ns;
      rec_capture.add(slot->stamps.captured_ns - c0);
      slot->seq = k++;
      slot->failed = false;
      captured_.fetch_add(1, std::memory_order_relaxed);
      if (options_.keep_newest) {
        if (FrameSlot* old = capture_newest.push(slot)) stash.push_back(old);
      } else {
        capture_fifo.push(slot);
      }
    }
    if (options_.keep_newest)
      capture_newest.close();
    else
      capture_fifo.close();
    running.fetch_sub(1);
  });

  // A processing stage: takes slots from `in` until closed, runs `fn` on those not failed,
  // forwards every slot to `out`.
  auto stage = [&](const char* name, auto pop, BlockingEdge<FrameSlot>& out, auto fn,
                   LatencyRecorder& rec, std::int64_t FrameStamps::*a, std::int64_t FrameStamps::*b) {
    work_.onThreadStart(name);
    // Frames ahead of a failure (already past this stage) are still published; after this
    // stage fails, every later frame is skipped here and downstream.
    bool this_stage_failed = false;
    for (;;) {
      FrameSlot* slot = nullptr;
      if (!pop(slot)) continue;
      if (!slot) break;
      if (this_stage_failed) slot->failed = true;
      if (!slot->failed) {
        slot->stamps.*a = steadyNowNs();
        Status s = fn(*slot);
        slot->stamps.*b = steadyNowNs();
        rec.add(slot->stamps.*b - slot->stamps.*a);
        if (!s) {
          slot->failed = true;
          this_stage_failed = true;
          fail(s);
        }
      }
      out.push(slot);
    }
    out.close();
    running.fetch_sub(1);
  };
  std::thread stereo([&] {
    auto pop = [&](FrameSlot*& s) {
      return options_.keep_newest ? capture_newest.pop(s, kPollTimeout)
                                  : capture_fifo.pop(s, kPollTimeout);
    };
    stage("stereo", pop, to_estimator, [&](FrameSlot& s) { return work_.stereo(s); }, rec_stereo,
          &FrameStamps::stereo_start_ns, &FrameStamps::stereo_end_ns);
  });
  std::thread estimator([&] {
    auto pop = [&](FrameSlot*& s) { return to_estimator.pop(s, kPollTimeout); };
    stage("estimator", pop, to_publisher, [&](FrameSlot& s) { return work_.estimate(s); },
          rec_estimate, &FrameStamps::estimate_start_ns, &FrameStamps::estimate_end_ns);
  });
  std::thread publisher([&] {
    work_.onThreadStart("publisher");
    bool publish_failed = false;
    for (;;) {
      FrameSlot* slot = nullptr;
      if (!to_publisher.pop(slot, kPollTimeout)) continue;
      if (!slot) break;
      if (publish_failed) slot->failed = true;
      if (!slot->failed) {
        slot->stamps.publish_start_ns = steadyNowNs();
        Status s = work_.publish(*slot);
        slot->stamps.published_ns = steadyNowNs();
        rec_publish.add(slot->stamps.published_ns - slot->stamps.publish_start_ns);
        if (!s) {
          publish_failed = true;
          fail(s);
          failed.fetch_add(1);
        } else {
          rec_e2e.add(slot->stamps.published_ns - slot->stamps.capture_ns);
          published_.fetch_add(1, std::memory_order_relaxed);
        }
      } else {
        failed.fetch_add(1);
      }
      free_slots.push(slot);
    }
    running.fetch_sub(1);
  });

  std::int64_t next_tick = steadyNowNs();
  while (running.load() > 0) {
    if (tick && steadyNowNs() >= next_tick) {
      tick();
      next_tick = steadyNowNs() + static_cast<std::int64_t>(tick_ms) * 1000000;
    }
    std::this_thread::sleep_for(milliseconds(std::min(tick_ms, 10)));
  }
  capture.join();
  stereo.join();
  estimator.join();
  publisher.join();
  if (tick) tick();

  report_.error = first_error;
  report_.failed = failed.load();
  report_.capture = rec_capture.summary();
  report_.stereo = rec_stereo.summary();
  report_.estimate = rec_estimate.summary();
  report_.publish = rec_publish.summary();
  report_.end_to_end = rec_e2e.summary();
  EdgeReport cap{"capture->stereo", 0, 0, 0, 0};
  if (options_.keep_newest) {
    cap.capacity = capture_newest.capacity();
    cap.max_depth = capture_newest.maxDepth();
    cap.drops = capture_newest.drops();
  } else {
    cap.capacity = capture_fifo.capacity();
    cap.max_depth = capture_fifo.maxDepth();
  }
  report_.dropped = cap.drops;
  report_.edges = {cap,
                   {"stereo->estimator", to_estimator.capacity(), to_estimator.maxDepth(), 0, 0},
                   {"estimator->publisher", to_publisher.capacity(), to_publisher.maxDepth(), 0, 0}};
  return first_error;
}

}  // namespace svslam::rt

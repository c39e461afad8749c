#pragma once
// Per-stage health of a running pipeline: since when each stage has been working on its
// current frame, and the stalls it had.
//
// A stretch is one stage's continuous work on one frame: it begins when the stage takes the
// frame (StageWork) and ends when the stage is done with it or starts waiting for another stage
// (StageWait; a new stretch begins when the wait is over). A stretch longer than the stall
// threshold is a stall of that stage. The stage stalled *now* is the one whose ongoing stretch is
// the longest of those beyond the threshold: a stage waiting on a stalled one is not working, so
// it does not count (the stereo stage waiting for the estimator's feedback, a queue full).
//
// Threads: each entry is written by its stage's own thread only (lock-free, no allocation);
// snapshot() may be called from any thread at any time (the control loop's health check, the
// stats publisher). After the run every stretch has ended and the snapshot is exact.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace svslam::rt {

struct StageStall {
  std::string stage;
  std::int64_t count = 0;  // stretches longer than the threshold, the ongoing one included
  double longest_ms = 0;   // the longest of them (an ongoing one: so far), ms
};

struct HealthSnapshot {
  std::string stalled_stage;       // the stage stalled now, "" = none
  double stalled_ms = 0;           // how long its ongoing stretch has lasted, ms (0: none)
  std::vector<StageStall> stalls;  // the stages with at least one stall, in graph order
  std::int64_t totalStalls() const;
};

class StageHealth {
 public:
  // One entry per name, in graph order (the runner: the source, then every stage).
  explicit StageHealth(std::vector<std::string> names);
  StageHealth(const StageHealth&) = delete;
  StageHealth& operator=(const StageHealth&) = delete;

  // Stretches longer than this are stalls; <= 0: none is (nothing is ever stalled).
  // Set before the run (not while stages work).
  void setStallThresholdNs(std::int64_t ns) { threshold_ns_ = ns; }
  std::int64_t stallThresholdNs() const { return threshold_ns_; }
  // Forgets every stretch and stall (before a run, no stage working).
  void reset();

  // Stage `index` begins / ends a stretch at now_ns (steady clock); its own thread only.
  void begin(std::size_t index, std::int64_t now_ns);
  void end(std::size_t index, std::int64_t now_ns);

  HealthSnapshot snapshot(std::int64_t now_ns) const;
  const std::vector<std::string>& names() const { return names_; }

 private:
  struct Entry {
    std::atomic<std::int64_t> since_ns{0};  // start of the ongoing stretch; 0 = none
    std::atomic<std::int64_t> stalls{0};    // ended stretches beyond the threshold
    std::atomic<std::int64_t> longest_ns{0};
  };
  std::vector<std::string> names_;
  std::unique_ptr<Entry[]> entries_;
  std::int64_t threshold_ns_ = 0;
};

// The runner's side: stage `index` of `health` works on a frame for the lifetime of the scope
// (one stretch), and a StageWait on this thread refers to it. Not nestable.
class StageWork {
 public:
  StageWork(StageHealth& health, std::size_t index);
  ~StageWork();
  StageWork(const StageWork&) = delete;
  StageWork& operator=(const StageWork&) = delete;
};

// A stage's side: the calling thread waits for another stage (or another thread) for the
// lifetime of the scope; its stretch ends here and a new one begins afterwards. A no-op outside
// a StageWork scope (tests calling a stage directly).
class StageWait {
 public:
  StageWait();
  ~StageWait();
  StageWait(const StageWait&) = delete;
  StageWait& operator=(const StageWait&) = delete;
};

}  // namespace svslam::rt

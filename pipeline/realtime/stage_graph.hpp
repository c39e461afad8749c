#pragma once
// The stages of a pipeline, declared as data: what each stage does to a frame, the policy of
// the edge into it, and its name (thread "svslam-<name>", stats key). PipelineRunner builds the
// threads, the lock-free SPSC edges and the preallocated frame slots from this list, or runs the
// same list on the calling thread (sequential). A linear chain:
//   source -> stages[0] -> stages[1] -> ... -> stages[n-1] (the sink)
// (or, when the last stage runs after publication, stages[n-2] is the sink and stages[n-1] a
// side branch fed from it).
// The source fills a free slot; each stage works on the slot it holds (no other stage holds it
// then); after the sink the slot is published and goes back to the source's free-slot ring.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/status.hpp"
#include "pipeline/realtime/frame_slot.hpp"

namespace svslam::rt {

enum class EdgePolicy {
  kBlocking,  // bounded FIFO of queue_capacity slots: the producer waits when full (no drop)
  kNewest,    // a mailbox holding the newest slot: an older one not yet taken is dropped and
              // counted (cameras, paced replays: a late frame is skipped, not queued)
};

struct SourceSpec {
  std::string name = "capture";
  // Reads the next pair into the slot (frame, ground truth); false at the end of the stream.
  std::function<Result<bool>(FrameSlot&)> read;
};

struct StageSpec {
  std::string name;
  // The stage's work on one frame, called from the stage's thread only. An error stops the run:
  // the frames ahead of it are still published, this one and every later one are not.
  std::function<Status(FrameSlot&)> work;
  EdgePolicy input = EdgePolicy::kBlocking;  // the edge from the stage before
  // A stage after publication (the last stage only, e.g. the mapper): the frame is published
  // (timed, counted) when the stage before it finishes; this stage then gets it as a side
  // branch. With a kNewest input it never delays the stages before it: a frame it has not
  // taken when the next one arrives is skipped (PipelineReport::after_publish_skipped).
  bool after_publish = false;
};

struct StageGraph {
  SourceSpec source;
  std::vector<StageSpec> stages;  // at least one; at most FrameStamps::kMaxStages
  // Called on each stage's own thread before its first frame, with the stage's name ("pipeline"
  // for the sequential run): thread name, affinity, priority.
  std::function<void(const std::string& stage)> on_thread_start;
  // Optional: called once on every pooled slot before the first frame (on the calling thread),
  // to size its buffers ahead of time. Without it a slot's first frame allocates and page-faults
  // its buffers (about 25 ms per slot at 1024x768), a latency spike on the first frames.
  std::function<void(FrameSlot&)> prepare_slot;
  Status validate() const;
};

}  // namespace svslam::rt

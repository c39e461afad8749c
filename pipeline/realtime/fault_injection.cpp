#include "pipeline/realtime/fault_injection.hpp"

#include <chrono>
#include <thread>
#include <utility>

namespace svslam::rt {

Status injectStall(StageGraph& graph, const StallFault& fault) {
  if (fault.stage.empty()) return Status::ok();
  if (fault.ms <= 0 || fault.frame < 0)
    return Status::invalidArgument("stall fault of stage '" + fault.stage +
                                   "': needs a frame >= 0 and a duration > 0 ms");
  const auto sleep = std::chrono::milliseconds(fault.ms);
  if (graph.source.name == fault.stage) {
    // The source's k-th read delivers the frame of capture sequence number k.
    graph.source.read = [read = std::move(graph.source.read), sleep, frame = fault.frame,
                         k = std::int64_t{0}](FrameSlot& slot) mutable {
      if (k++ == frame) std::this_thread::sleep_for(sleep);
      return read(slot);
    };
    return Status::ok();
  }
  for (StageSpec& s : graph.stages) {
    if (s.name != fault.stage) continue;
    s.work = [work = std::move(s.work), sleep, frame = fault.frame,
              fired = false](FrameSlot& slot) mutable {
      if (!fired && slot.seq >= frame) {
        fired = true;
        std::this_thread::sleep_for(sleep);
      }
      return work(slot);
    };
    return Status::ok();
  }
  std::string names = graph.source.name;
  for (const StageSpec& s : graph.stages) names += ", " + s.name;
  return Status::invalidArgument("stall fault: this pipeline has no stage '" + fault.stage +
                                 "' (stages: " + names + ")");
}

}  // namespace svslam::rt

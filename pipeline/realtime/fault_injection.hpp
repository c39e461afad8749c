#pragma once
// Test hooks: faults injected into a stage graph, to exercise the health checks of a running
// pipeline (the `pipeline.fault.*` keys of `svslam run`, docs/service.md "Injected faults").
// Never set in production: every fault is off by default.
#include <cstdint>
#include <string>

#include "core/status.hpp"
#include "pipeline/realtime/stage_graph.hpp"

namespace svslam::rt {

// One stage sleeps once, as if stuck: on the first frame whose capture sequence number is at
// least `frame` (the source: its read of that frame), for `ms` milliseconds, inside the stage's
// work (the health check sees the stage busy).
struct StallFault {
  std::string stage;       // the source's or a stage's name; "" = no fault
  std::int64_t frame = 0;  // capture sequence number, >= 0
  int ms = 0;              // sleep, milliseconds, > 0
};

// Wraps the work of the stage `fault.stage` of `graph` (no-op when the name is empty). Error
// naming the stage when the graph has none of that name.
Status injectStall(StageGraph& graph, const StallFault& fault);

}  // namespace svslam::rt

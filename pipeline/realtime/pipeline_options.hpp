#pragma once
// How PipelineRunner runs a stage graph. The `pipeline.sequential`, `pipeline.rate_hz` and
// `pipeline.queue_capacity` keys of the configuration read straight into this struct
// (config::PipelineConfig::runner).
#include "core/status.hpp"

namespace svslam::rt {

struct PipelineOptions {
  bool sequential = false;  // every stage on the calling thread (same outputs as threaded)
  double rate_hz = 0.0;     // replay a recorded source at this rate, Hz; 0 = as fast as possible
  int queue_capacity = 2;   // frames per blocking inter-stage edge, 1..64
  Status validate() const;
};

}  // namespace svslam::rt

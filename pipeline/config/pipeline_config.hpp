#pragma once
// The real-time part of the `svslam run` configuration: the pipeline (threads, queues, pacing,
// scheduling), LCM publishing and the service life cycle. Keys documented in config/svslam.yaml.
#include <string>

#include "core/status.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "pipeline/service/scheduling.hpp"

namespace svslam::config {

class ConfigReader;

struct PipelineConfig {
  bool sequential = false;  // every stage on one thread (same outputs as threaded)
  double rate_hz = 0.0;     // replay a recorded source at this rate; 0 = as fast as possible
  // Capture edge: "newest" keeps the newest frame and counts drops (cameras, paced replays),
  // "block" waits for the stereo stage (no drop); "auto": newest for live sources (size -1) and
  // paced replays, block otherwise.
  std::string capture_policy = "auto";
  int queue_capacity = 2;   // frames per inter-stage queue, 1..64
  // Read the whole recorded sequence into memory before the run (a paced replay then measures
  // the pipeline, not the disk or the synthetic renderer). Ignored for live sources.
  bool preload = false;
  double progress_period_s = 10.0;  // progress line on stderr every this many s (0 = never)
  // Per stage thread: CPU affinity and SCHED_FIFO priority (0 = normal scheduling).
  service::ThreadScheduling capture, stereo, estimator, publisher;
};

struct LcmConfig {
  bool enabled = false;       // publish poses / stats / map and listen for commands
  drivers::LcmParams params;       // url and channel names
  double stats_period_s = 1.0;  // stats and map summary every this many s
};

struct ServiceConfig {
  // READY=1 to systemd after the first published pose ("first_pose") or when the pipeline
  // starts ("start").
  std::string ready = "first_pose";
  // The health check pings the watchdog only while frames complete; a pipeline that has
  // published nothing for this long (and is not paused) stops pinging, s.
  double stall_timeout_s = 5.0;
};

// Reads the pipeline.*, lcm.* and service.* keys.
Status readPipelineConfig(ConfigReader& r, PipelineConfig& p, LcmConfig& l, ServiceConfig& s);

}  // namespace svslam::config

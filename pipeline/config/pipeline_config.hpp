#pragma once
// The real-time part of the `svslam run` configuration: the pipeline (threads, queues, pacing,
// scheduling), LCM publishing and the service life cycle. Their keys, units, ranges and docs
// are declared in pipeline_config_keys.cpp.
#include <string>

#include "core/status.hpp"
#include "drivers/lcm/command_gate.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "pipeline/config/enum_names.hpp"
#include "pipeline/realtime/pipeline_options.hpp"
#include "pipeline/service/scheduling.hpp"

namespace svslam::config {

// Capture edge: kNewest keeps the newest frame and counts drops (cameras, paced replays),
// kBlock waits for the stereo stage (no drop); kAuto: newest for live sources (size -1) and
// paced replays, block otherwise.
enum class CapturePolicy { kAuto, kNewest, kBlock };
inline constexpr EnumNames<CapturePolicy, 3> kCapturePolicyNames{
    {{"auto", CapturePolicy::kAuto},
     {"newest", CapturePolicy::kNewest},
     {"block", CapturePolicy::kBlock}}};
const char* toString(CapturePolicy p);

// When READY=1 goes to systemd: after the first published pose, or when the pipeline starts.
enum class ReadyWhen { kFirstPose, kStart };
inline constexpr EnumNames<ReadyWhen, 2> kReadyWhenNames{
    {{"first_pose", ReadyWhen::kFirstPose}, {"start", ReadyWhen::kStart}}};
const char* toString(ReadyWhen r);

// pipeline.fault.*: test hooks (docs/service.md "Injected faults"), off by default. A stage of
// `svslam run` sleeps once, as if stuck (rt::StallFault), so that the health check's stall
// reports can be tested on the real pipeline.
enum class FaultStage { kNone, kCapture, kStereo, kEstimator, kPublisher, kMapper };
inline constexpr EnumNames<FaultStage, 6> kFaultStageNames{{{"none", FaultStage::kNone},
                                                            {"capture", FaultStage::kCapture},
                                                            {"stereo", FaultStage::kStereo},
                                                            {"estimator", FaultStage::kEstimator},
                                                            {"publisher", FaultStage::kPublisher},
                                                            {"mapper", FaultStage::kMapper}}};
const char* toString(FaultStage f);
struct FaultConfig {
  FaultStage stall_stage = FaultStage::kNone;  // the stage that sleeps once; kNone = no fault
  int stall_frame = 10;  // on the first frame whose capture sequence number is at least this
  int stall_ms = 2000;   // for this long, ms
  // The estimator is reset before this frame (source index) as if the LCM `reset` command had
  // arrived then; -1 = never.
  int reset_frame = -1;
};

struct PipelineConfig {
  rt::PipelineOptions runner;  // sequential, rate_hz, queue_capacity: given to the runner as is
  CapturePolicy capture_policy = CapturePolicy::kAuto;  // the capture edge's queue policy
  // Read the whole recorded sequence into memory before the run (a paced replay then measures
  // the pipeline, not the disk or the synthetic renderer). Ignored for live sources.
  bool preload = false;
  // Replays of the preloaded sequence in one run (soak tests), the frame index and clock running
  // on (drivers::PreloadedSource::setLoops). Needs preload when > 1.
  int replay_loops = 1;
  // latency.txt in the output folder: per published frame, its capture sequence number and the
  // capture-to-publish latency (ms), flushed per line.
  bool latency_log = false;
  double progress_period_s = 10.0;  // progress line on stderr every this many s (0 = never)
  // Per stage thread: CPU affinity and SCHED_FIFO priority (0 = normal scheduling).
  service::ThreadScheduling capture, stereo, estimator, publisher, mapper;
  FaultConfig fault;  // test hooks only
};

struct LcmConfig {
  bool enabled = false;                 // publish poses / stats / map and listen for commands
  drivers::LcmParams params;            // url and channel names
  double stats_period_s = 1.0;          // stats and map summary every this many s
  drivers::CommandAuthParams commands;  // lcm.commands.*: who may command the service
};

struct ServiceConfig {
  ReadyWhen ready = ReadyWhen::kFirstPose;  // when READY=1 goes to systemd
  // The health check pings the watchdog only while frames complete and no stage is stalled: a
  // pipeline that has published nothing for this long (and is not paused), or a stage that has
  // been working on one frame for this long, stops the pings, s.
  double stall_timeout_s = 5.0;
};

// The checks across keys of pipeline.* and lcm.* (each key's own range is checked when read);
// `file` prefixes the message.
Status checkPipelineConfig(const std::string& file, const PipelineConfig& p, const LcmConfig& l);

}  // namespace svslam::config

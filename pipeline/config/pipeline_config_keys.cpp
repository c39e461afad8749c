// The keys of the pipeline, lcm and service sections: field, unit, range and doc of each, once.
#include <cmath>

#include "pipeline/config/config_keys.hpp"

namespace svslam::config {
namespace {

// pipeline.scheduling.<stage>: CPU affinity (a list of CPU indices) and SCHED_FIFO priority.
template <typename F>
ConfigSection scheduling(const std::string& stage, F thread) {
  ConfigKey cpus{"cpus", "", "0..1023 each", "CPUs the thread may run on; [] = any", {}, {}};
  cpus.read = [thread](ConfigReader& r, const std::string& key, RunConfig& c) {
    service::ThreadScheduling& t = thread(c);
    std::vector<double> list(t.cpus.begin(), t.cpus.end());
    SVSLAM_TRY(r.read(key, list));
    t.cpus.clear();
    for (double x : list) {
      if (!(x >= 0 && x <= 1023 && x == std::floor(x)))
        return Status::invalidArgument(r.name() + ": key '" + key +
                                       "' holds a value that is not a CPU index (0..1023)");
      t.cpus.push_back(static_cast<int>(x));
    }
    return Status::ok();
  };
  cpus.value = [thread](const RunConfig& c) { return formatValue(thread(c).cpus); };
  auto priority = [thread](auto& c) -> auto& { return thread(c).fifo_priority; };
  return {"pipeline.scheduling." + stage,
          "",
          {
              std::move(cpus),
              number("fifo_priority", priority, 0, 99, "",
                     "SCHED_FIFO priority; 0 = normal scheduling"),
          }};
}

ConfigSection pipelineSection() {
  ConfigSection s{"pipeline", "the real-time pipeline (pipeline/realtime/pipeline_runner.hpp)", {}};
  s.keys = {
      flag("sequential", SVSLAM_FIELD(pipeline.runner.sequential),
           "true: every stage on one thread (same outputs); --sequential"),
      number("rate_hz", SVSLAM_FIELD(pipeline.runner.rate_hz), 0, 10000, "Hz",
             "replay a recorded source at this rate, frames stamped as if captured then; "
             "0 = as fast as possible; --rate"),
      choice("capture_policy", SVSLAM_FIELD(pipeline.capture_policy), kCapturePolicyNames,
             "newest: the capture edge keeps the newest frame and counts drops; block: capture "
             "waits (no drop); auto: newest for live sources and paced replays, else block"),
      number("queue_capacity", SVSLAM_FIELD(pipeline.runner.queue_capacity), 1, 64, "",
             "frames per inter-stage queue"),
      flag("preload", SVSLAM_FIELD(pipeline.preload),
           "read the recorded sequence into memory first; --preload"),
      number("replay_loops", SVSLAM_FIELD(pipeline.replay_loops), 1, 1000000, "",
             "replays of the preloaded sequence in one run, frame index and clock running on "
             "(needs preload when > 1); --loops"),
      flag("latency_log", SVSLAM_FIELD(pipeline.latency_log),
           "latency.txt: per published frame its sequence number and capture-to-publish "
           "latency, ms"),
      number("progress_period_s", SVSLAM_FIELD(pipeline.progress_period_s), 0, 1e6, "s",
             "progress line on stderr every this many s; 0 = never"),
  };
  return s;
}

ConfigSection faultSection() {
  ConfigSection s{
      "pipeline.fault", "test hooks: injected faults, off by default (docs/service.md)", {}};
  s.keys = {
      choice("stall_stage", SVSLAM_FIELD(pipeline.fault.stall_stage), kFaultStageNames,
             "test hook: this stage sleeps stall_ms once, as if stuck (the health check reports "
             "it); none = no fault"),
      number("stall_frame", SVSLAM_FIELD(pipeline.fault.stall_frame), 0, 100000000, "",
             "test hook: on the first frame whose capture sequence number is at least this"),
      number("stall_ms", SVSLAM_FIELD(pipeline.fault.stall_ms), 1, 600000, "ms",
             "test hook: how long the stage sleeps"),
      number("reset_frame", SVSLAM_FIELD(pipeline.fault.reset_frame), -1, 100000000, "",
             "test hook: the estimator is reset before this source frame, as by the LCM reset "
             "command; -1 = never"),
  };
  return s;
}

ConfigSection lcmSection() {
  ConfigSection s{"lcm", "LCM publishing and commands (docs/lcm.md)", {}};
  s.keys = {
      flag("enabled", SVSLAM_FIELD(lcm.enabled),
           "true (or --lcm-url): publish poses, stats, map; listen for commands"),
      text("url", SVSLAM_FIELD(lcm.params.url), "LCM provider URL"),
      text("pose_channel", SVSLAM_FIELD(lcm.params.pose_channel),
           "svslam_lcm.pose_t, every frame, with the 6x6 covariance"),
      text("stats_channel", SVSLAM_FIELD(lcm.params.stats_channel),
           "svslam_lcm.stats_t, every stats_period_s"),
      text("map_channel", SVSLAM_FIELD(lcm.params.map_channel),
           "svslam_lcm.map_summary_t, every stats_period_s (ekf mode)"),
      text("map_tile_channel", SVSLAM_FIELD(lcm.params.map_tile_channel),
           "svslam_lcm.map_tile_t, the elevation map tiles changed, every map.publish_period_s"),
      text("map_tile_optimized_channel", SVSLAM_FIELD(lcm.params.map_tile_optimized_channel),
           "svslam_lcm.map_tile_t, the whole elevation map re-placed after loop-closing "
           "corrections (loop.enabled), at most every map.replace_period_s"),
      text("correction_channel", SVSLAM_FIELD(lcm.params.correction_channel),
           "svslam_lcm.pose_correction_t, after each loop closure (loop.enabled)"),
      text("command_channel", SVSLAM_FIELD(lcm.params.command_channel),
           "svslam_lcm.command_t: reset | save_map | pause | resume | shutdown (see "
           "lcm.commands)"),
      text("status_channel", SVSLAM_FIELD(lcm.params.status_channel),
           "svslam_lcm.command_status_t answers"),
      text("altitude_channel", SVSLAM_FIELD(lcm.params.altitude_channel),
           "read: svslam_lcm.altitude_t, the camera's height above the ground (mode mono with "
           "slam.mono_scale altitude)"),
      number("stats_period_s", SVSLAM_FIELD(lcm.stats_period_s), 0.01, 3600, "s",
             "stats and map summary every this many s"),
  };
  return s;
}

ConfigSection lcmCommandsSection() {
  ConfigSection s{"lcm.commands", "who may command the service over LCM (docs/lcm.md)", {}};
  s.keys = {
      flag("enabled", SVSLAM_FIELD(lcm.commands.enabled),
           "false: every command is refused and counted; true: needs token_file"),
      text("token_file", SVSLAM_FIELD(lcm.commands.token_file),
           "file holding the shared token commands must carry; mode 0600/0400 (no group or "
           "other access), else the service refuses to start"),
      number("max_per_s", SVSLAM_FIELD(lcm.commands.max_per_s), 0.1, 1000, "1/s",
             "authenticated commands per second, bursts of as many; the excess is refused"),
  };
  return s;
}

ConfigSection serviceSection() {
  ConfigSection s{"service", "life cycle under systemd (docs/service.md)", {}};
  s.keys = {
      choice("ready", SVSLAM_FIELD(service.ready), kReadyWhenNames,
             "READY=1 after the first published pose, or when the pipeline starts"),
      number("stall_timeout_s", SVSLAM_FIELD(service.stall_timeout_s), 0.1, 3600, "s",
             "no pose for this long (not paused), or a stage working on one frame for this long: "
             "the health check stops pinging the watchdog and reports the stage"),
  };
  return s;
}

}  // namespace

std::vector<ConfigSection> pipelineConfigSections() {
  return {pipelineSection(),
          {"pipeline.scheduling",
           "per stage thread; a refused FIFO priority degrades to normal scheduling with a warning",
           {}},
          scheduling("capture", SVSLAM_FIELD(pipeline.capture)),
          scheduling("stereo", SVSLAM_FIELD(pipeline.stereo)),
          scheduling("estimator", SVSLAM_FIELD(pipeline.estimator)),
          scheduling("publisher", SVSLAM_FIELD(pipeline.publisher)),
          scheduling("mapper", SVSLAM_FIELD(pipeline.mapper)),
          faultSection(),
          lcmSection(),
          lcmCommandsSection(),
          serviceSection()};
}

const std::vector<ConfigSection>& allConfigSections() {
  static const std::vector<ConfigSection> kAll = [] {
    std::vector<ConfigSection> all = runConfigSections();
    for (ConfigSection& s : pipelineConfigSections()) all.push_back(std::move(s));
    return all;
  }();
  return kAll;
}

}  // namespace svslam::config

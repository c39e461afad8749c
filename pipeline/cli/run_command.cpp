// svslam run: the real-time pipeline over a source (recorded or live), writing trajectories,
// covariances, the map and stats, publishing on LCM, under systemd when started as a service.
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <system_error>
#include <tuple>
#include <utility>
#include <vector>

#include "drivers/lcm/command_token.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "drivers/source/preloaded_source.hpp"
#include "drivers/source/stereo_source.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/fault_injection.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/realtime/slam_stages.hpp"
#include "pipeline/run/run_outputs.hpp"
#include "pipeline/run/run_summary.hpp"
#include "pipeline/service/sd_notify.hpp"
#include "pipeline/service/stop_signal.hpp"

namespace svslam::cli {
namespace {

void logLine(const std::string& msg) {
  std::fprintf(stderr, "svslam run: %s\n", msg.c_str());
  std::fflush(stderr);
}

// One "warning: ..." log line per line of `lines`.
void logWarnings(const std::string& lines) {
  std::size_t start = 0;
  while (start < lines.size()) {
    std::size_t end = lines.find('\n', start);
    if (end == std::string::npos) end = lines.size();
    if (end > start) logLine("warning: " + lines.substr(start, end - start));
    start = end + 1;
  }
}

// Applies the command-line overrides to the configuration.
Status applyOverrides(const ArgParser& p, config::RunConfig& cfg) {
  if (p.has("max-frames")) {
    auto n = p.getInt("max-frames", 0, 100000000);
    if (!n) return n.status();
    cfg.max_frames = *n;
  }
  if (p.has("threads")) {
    auto n = p.getInt("threads", 1, 256);
    if (!n) return n.status();
    config::applyThreads(cfg, *n);
  }
  if (p.has("mode") && !config::parseName(config::kEstimatorModeNames, p.get("mode"), cfg.mode))
    return Status::invalidArgument("--mode: unknown mode '" + p.get("mode") + "' (use " +
                                   config::nameList(config::kEstimatorModeNames) + ")");
  if (p.flag("sequential")) cfg.pipeline.runner.sequential = true;
  if (p.flag("preload")) cfg.pipeline.preload = true;
  if (p.has("loops")) {
    auto n = p.getInt("loops", 1, 1000000);
    if (!n) return n.status();
    cfg.pipeline.replay_loops = *n;
  }
  if (p.has("rate")) {
    auto r = p.getDouble("rate");
    if (!r) return r.status();
    if (!(*r >= 0.0 && *r <= 10000.0))
      return Status::invalidArgument("--rate: must be in [0, 10000] Hz (0 = as fast as possible)");
    cfg.pipeline.runner.rate_hz = *r;
  }
  if (p.has("lcm-url")) {
    cfg.lcm.enabled = true;
    cfg.lcm.params.url = p.get("lcm-url");
  }
  return Status::ok();
}

// Applies the LCM commands received since the last tick and answers each on the status channel.
void handleCommands(drivers::LcmLink& lcm, rt::SlamStages& work, rt::PipelineControl& control) {
  std::vector<drivers::Command> cmds;
  if (!lcm.pollCommands(0, cmds)) return;
  for (const drivers::Command& c : cmds) {
    drivers::CommandStatus st;
    st.t_ns = c.t_ns;
    st.seq = c.seq;
    st.ok = true;
    switch (c.kind) {
      case drivers::CommandKind::kReset:
        st.command = "reset";
        work.requestReset();
        st.message = "the estimator restarts at the next frame (new map, pose at identity)";
        break;
      case drivers::CommandKind::kSaveMap:
        st.command = "save_map";
        work.requestSaveMap(c.argument, c.seq);
        continue;  // answered by the estimator once written
      case drivers::CommandKind::kPause:
        st.command = "pause";
        control.pause = true;
        st.message = "capture paused";
        break;
      case drivers::CommandKind::kResume:
        st.command = "resume";
        control.pause = false;
        st.message = "capture resumed";
        break;
      case drivers::CommandKind::kShutdown:
        st.command = "shutdown";
        service::requestStop();
        st.message = "stopping: draining the pipeline";
        break;
    }
    logLine("command " + st.command + " (seq " + std::to_string(c.seq) + ")");
    (void)lcm.publishCommandStatus(st);
  }
}

// Logs refused commands (commands_refused by reason, the last one) at most once per
// kPeriodNs, so a flood of refused commands gives one line a second, not one per command.
class RefusedCommandLog {
 public:
  static constexpr std::int64_t kPeriodNs = 1'000'000'000;

  // now_ns: steady clock, ns. force: log now whatever the time of the last line.
  void update(const drivers::LcmLink& lcm, std::int64_t now_ns, bool force = false) {
    const drivers::CommandCounts c = lcm.commandCounts();
    if (c.refusedTotal() == logged_.refusedTotal()) return;
    if (!force && now_ns < next_ns_) return;
    std::string by;
    for (int k = 0; k < drivers::kNumCommandRefusals; ++k) {
      const std::int64_t n = c.refused[k] - logged_.refused[k];
      if (n > 0)
        by += std::string(by.empty() ? "" : ", ") + std::to_string(n) + " " +
              drivers::refusalName(static_cast<drivers::CommandRefusal>(k));
    }
    std::string last = lcm.lastRefused();
    if (c.refusedBy(drivers::CommandRefusal::kMalformed) >
        logged_.refusedBy(drivers::CommandRefusal::kMalformed))
      last += (last.empty() ? "" : "; ") + lcm.lastMalformed();
    logLine("refused " + std::to_string(c.refusedTotal() - logged_.refusedTotal()) +
            " LCM command(s) (" + by + "); last: " + last);
    logged_ = c;
    next_ns_ = now_ns + kPeriodNs;
  }

 private:
  drivers::CommandCounts logged_;
  std::int64_t next_ns_ = 0;
};

std::string seconds(double ms) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", ms * 1e-3);
  return buf;
}

// The health check's view of stage stalls (realtime/stage_health.hpp): says on stderr and in
// systemd's STATUS= when a stage stalls and when it recovers.
class StallCheck {
 public:
  explicit StallCheck(double timeout_s) : timeout_s_(timeout_s) {}
  // True while a stage is stalled (the caller stops the watchdog pings).
  bool update(const rt::StageHealth& health, std::int64_t now_ns,
              service::ServiceNotifier& notifier) {
    const rt::HealthSnapshot h = health.snapshot(now_ns);
    if (h.stalled_stage == stalled_ && h.totalStalls() == total_) return !stalled_.empty();
    for (const rt::StageStall& st : h.stalls) {
      std::int64_t& seen = seen_[st.stage];
      const bool now_stalled = st.stage == h.stalled_stage;
      if (st.stage == stalled_ && !now_stalled) {
        logLine("stage '" + st.stage + "' recovered: stalled " + std::to_string(st.count) +
                " time(s), the longest " + seconds(st.longest_ms));
        if (h.stalled_stage.empty())
          notifier.status("tracking; stage " + st.stage + " stalled " + std::to_string(st.count) +
                          " time(s), the longest " + seconds(st.longest_ms));
      } else if (now_stalled && st.stage != stalled_) {
        logLine("stage '" + st.stage + "' stalled: working on one frame for " +
                seconds(h.stalled_ms) + " (service.stall_timeout_s " + seconds(timeout_s_ * 1e3) +
                "); watchdog pings stopped");
        notifier.status("stalled: stage " + st.stage + " working on one frame for more than " +
                        seconds(timeout_s_ * 1e3) + "; watchdog pings stopped");
      } else if (!now_stalled && st.count > seen) {  // began and ended between two checks
        logLine("stage '" + st.stage + "' stalled (seen after it ended): " +
                std::to_string(st.count) + " time(s), the longest " + seconds(st.longest_ms));
      }
      seen = st.count;
    }
    stalled_ = h.stalled_stage;
    total_ = h.totalStalls();
    return !stalled_.empty();
  }

 private:
  double timeout_s_;
  std::string stalled_;  // the stage reported stalled; "" = none
  std::int64_t total_ = 0;
  std::map<std::string, std::int64_t> seen_;  // stalls per stage already reported
};

// The token of lcm.commands (read from its file) when LCM and commands are on; "" otherwise.
Result<std::string> commandToken(const config::RunConfig& cfg) {
  if (!cfg.lcm.enabled || !cfg.lcm.commands.enabled) return std::string();
  auto token = drivers::readCommandToken(cfg.lcm.commands.token_file);
  if (!token)
    return Status(token.status().code(),
                  "lcm.commands.enabled is true but the " + token.status().message());
  return token;
}

// The outputs of a run stopped before its source delivered a frame (a stop signal while an
// lcm: source waited for its first frame): empty trajectories and stats.json; exit 0.
int finishWithoutFrames(const config::RunConfig& cfg, const std::string& source_spec,
                        const std::string& out_dir, const Status& why) {
  logLine("stopped before the first frame: " + why.message());
  auto fail = [](const Status& s) { return reportFailure("run", s); };
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec || !std::filesystem::is_directory(out_dir))
    return fail(Status::ioError("cannot create output folder '" + out_dir + "'"));
  if (Status s = run::clearRunOutputs(out_dir); !s) return fail(s);
  for (const char* name : {run::files::kTrajectoryKitti, run::files::kTrajectoryTum})
    if (Status s = run::writeFileAtomic(out_dir + "/" + name, ""); !s) return fail(s);
  const std::string stats = run::statsJson(cfg, source_spec, run::RunSummary{}, EstimatorOutputs{},
                                           run::StageTimes(1), rt::PipelineReport{}, "");
  if (Status s = run::writeFileAtomic(out_dir + "/" + run::files::kStats, stats); !s)
    return fail(s);
  JsonObject j;
  j.add("source", source_spec)
      .add("mode", config::toString(cfg.mode))
      .add("out", out_dir)
      .add("frames", 0)
      .add("stopped_by_signal", service::stopRequested());
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace

int runPipeline(const std::vector<std::string>& args) {
  ArgParser p(
      "run",
      "Runs the real-time pipeline (capture -> stereo -> estimator -> publisher, one\n"
      "thread each) over a source and writes to the output folder: trajectory_kitti.txt\n"
      "(3x4 [R|t] per frame, left camera in the first left camera's frame),\n"
      "trajectory_tum.txt, stats.json (frames, frames without a pose and why, per-stage\n"
      "time p50/p99/max, end-to-end latency capture -> pose published, queues, drops) and,\n"
      "when the source knows it, groundtruth_kitti.txt. In ekf mode (default) also\n"
      "pose_covariance.txt (6x6 per frame, row-major, [rot rad, trans m]) and\n"
      "landmarks.ply (position + 1-sigma radii). With lcm.enabled (or --lcm-url) poses\n"
      "with covariance, stats and the map summary go out on LCM; commands are taken only\n"
      "with lcm.commands.enabled and the token of lcm.commands.token_file.\n"
      "SIGTERM/SIGINT/SIGHUP stop capture, drain the frames in flight, write every output\n"
      "and exit 0 (also during --preload or while a source waits for its first frame).\n"
      "An output folder used before loses the files of the earlier run that this run\n"
      "writes (trajectories, stats.json, map files...); other files stay. Under\n"
      "systemd (Type=notify): READY=1 after the first pose, WATCHDOG=1 while frames\n"
      "complete and no stage works on one frame for longer than service.stall_timeout_s\n"
      "(such a stage is named on stderr, in STATUS= and in the stats). A failed write\n"
      "(disk full) exits 1 naming the file. Prints a JSON summary.");
  p.addOption("source", "SRC",
              "kitti:DIR, euroc:DIR, synthetic[:key=value,...], v4l2:..., libcamera:... or "
              "lcm:CHANNEL (default: the config's 'source', else synthetic)");
  p.addOption("config", "FILE", "YAML configuration (documented example: config/svslam.yaml)");
  p.addOption("out", "DIR", "output folder (created if missing)", "svslam_out");
  p.addOption("max-frames", "N", "stop after N frames (0 = all; overrides the config)");
  p.addOption("threads", "T", "worker threads inside the stereo stage (overrides the config)");
  p.addOption("mode", "ekf|vo|mono",
              "ekf: EKF SLAM over pose and landmarks; vo: pure visual odometry; mono: EKF SLAM "
              "from the left camera, its scale from the first stereo pair, an altimeter on LCM "
              "or none (slam.mono_scale) (overrides the config; default ekf)");
  p.addFlag("sequential", "run every stage on one thread (same outputs as the threaded run)");
  p.addOption("rate", "HZ",
              "replay a recorded source in real time at HZ frames per second (frames stamped as "
              "if captured then; 0 = as fast as possible, the default)");
  p.addFlag("preload", "read the whole recorded sequence into memory before the run");
  p.addOption("loops", "N",
              "with --preload: replay the sequence N times in one run, frame index and clock "
              "running on (soak tests; overrides the config)");
  p.addOption("lcm-url", "URL",
              "publish on LCM at URL (enables lcm; e.g. udpm://239.255.76.67:7667?ttl=0)");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("run", s); };
  // First: a stop signal from now on ends the run in order (exit 0, every output whole).
  if (Status s = service::installStopSignalHandlers(); !s) return fail(s);

  config::RunConfig cfg;
  if (Status s = config::loadRunConfig(p.has("config") ? p.get("config") : "", cfg); !s)
    return fail(s);
  if (Status s = applyOverrides(p, cfg); !s) return fail(s);
  // Commands enabled without a usable token file: no start at all.
  auto command_token = commandToken(cfg);
  if (!command_token) return fail(command_token.status());
  {
    const long ncpu = ::sysconf(_SC_NPROCESSORS_CONF);
    const std::pair<const char*, const service::ThreadScheduling*> stages[] = {
        {"capture", &cfg.pipeline.capture},
        {"stereo", &cfg.pipeline.stereo},
        {"estimator", &cfg.pipeline.estimator},
        {"publisher", &cfg.pipeline.publisher},
        {"mapper", &cfg.pipeline.mapper}};
    for (const auto& [name, sched] : stages)
      for (int c : sched->cpus)
        if (ncpu > 0 && c >= ncpu)
          return fail(Status::invalidArgument(
              std::string("pipeline.scheduling.") + name + ".cpus: CPU " + std::to_string(c) +
              " does not exist (this machine has CPUs 0.." + std::to_string(ncpu - 1) + ")"));
  }
  const std::string source_spec = p.has("source") ? p.get("source") : cfg.source;
  const std::string out_dir = p.get("out");
  // Also polled by a live source during the run (v4l2: waiting for an unplugged camera).
  std::atomic<bool> stopped_while_opening{false};
  const drivers::StopQuery stop = [&] { return stopped_while_opening = service::stopRequested(); };
  auto opened = drivers::openStereoSource(source_spec, stop);
  if (!opened && stopped_while_opening)
    return finishWithoutFrames(cfg, source_spec, out_dir, opened.status());
  if (!opened) return fail(opened.status());
  std::unique_ptr<drivers::StereoSource> source = std::move(*opened);
  if (const int n = source->skippedFrames(); n > 0)
    logLine("warning: " + std::to_string(n) +
            " frame(s) of the source skipped: " + source->skippedFramesDetail());
  const bool live = source->size() < 0;
  if (cfg.pipeline.replay_loops > 1 && (!cfg.pipeline.preload || live))
    return fail(Status::invalidArgument(
        "pipeline.replay_loops (--loops) > 1 needs a recorded source read into memory "
        "(pipeline.preload, --preload)"));
  if (cfg.pipeline.preload && !live) {
    logLine("reading the sequence into memory");
    auto pre = drivers::preload(std::move(source), cfg.max_frames, stop);
    if (!pre) return fail(pre.status());
    if (Status s = (*pre)->setLoops(cfg.pipeline.replay_loops); !s) return fail(s);
    source = std::move(*pre);
  }

  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec || !std::filesystem::is_directory(out_dir))
    return fail(Status::ioError("cannot create output folder '" + out_dir + "'"));
  if (Status s = run::clearRunOutputs(out_dir); !s) return fail(s);

  std::unique_ptr<drivers::LcmLink> lcm;
  if (cfg.lcm.enabled) {
    const drivers::CommandAuthParams& auth = cfg.lcm.commands;
    auto l = drivers::LcmLink::open(
        cfg.lcm.params, drivers::CommandGate(auth.enabled, *command_token, auth.max_per_s));
    if (!l) return fail(l.status());
    lcm = std::move(*l);
  }
  rt::SlamStages work(cfg, *source, out_dir, lcm.get());
  if (Status s = work.init(); !s) return fail(s);

  const rt::PipelineOptions& opts = cfg.pipeline.runner;
  if (Status s = opts.validate(); !s) return fail(s);
  const bool keep_newest =
      cfg.pipeline.capture_policy == config::CapturePolicy::kNewest ||
      (cfg.pipeline.capture_policy == config::CapturePolicy::kAuto && (live || opts.rate_hz > 0));
  rt::StageGraph graph =
      work.graph(keep_newest ? rt::EdgePolicy::kNewest : rt::EdgePolicy::kBlocking);
  if (const config::FaultConfig& f = cfg.pipeline.fault;
      f.stall_stage != config::FaultStage::kNone) {
    const rt::StallFault fault{config::toString(f.stall_stage), f.stall_frame, f.stall_ms};
    if (Status s = rt::injectStall(graph, fault); !s)
      return fail(Status::invalidArgument("pipeline.fault.stall_stage: " + s.message()));
    logLine("test hook: stage '" + fault.stage + "' will stall " + std::to_string(fault.ms) +
            " ms at frame " + std::to_string(fault.frame));
  }
  rt::PipelineRunner runner(opts, std::move(graph));
  const std::int64_t stall_ns = static_cast<std::int64_t>(cfg.service.stall_timeout_s * 1e9);
  runner.setStallThresholdNs(stall_ns);
  work.setTimings(&runner.timings());
  work.setHealth(&runner.health());
  std::vector<std::unique_ptr<rt::FrameSlot>> slots;
  const StereoCalibration& calib = source->calibration();
  for (int i = 0; i < runner.slotsNeeded(); ++i) {
    auto slot = std::make_unique<rt::FrameSlot>();
    slot->frame.left.resize(calib.width, calib.height);
    slot->frame.right.resize(calib.width, calib.height);
    slots.push_back(std::move(slot));
  }
  work.setMaxFrames(cfg.max_frames);

  service::ServiceNotifier notifier;
  const std::int64_t wd_interval = notifier.watchdogIntervalNs();
  service::HealthWatchdog watchdog(wd_interval, stall_ns);
  StallCheck stall_check(cfg.service.stall_timeout_s);
  rt::PipelineControl control;
  bool ready_sent = false, stopping_sent = false;
  if (cfg.service.ready == config::ReadyWhen::kStart) {
    notifier.ready("started");
    ready_sent = true;
  }
  std::int64_t last_published = 0;
  RefusedCommandLog refused_log;
  const std::int64_t progress_ns = static_cast<std::int64_t>(cfg.pipeline.progress_period_s * 1e9);
  std::int64_t next_progress = rt::steadyNowNs() + progress_ns;
  auto tick = [&] {
    const std::int64_t now = rt::steadyNowNs();
    logWarnings(work.takeWarnings());
    if (service::stopRequested() && !control.stop) {
      control.stop = true;
      if (!stopping_sent) {
        notifier.stopping();
        stopping_sent = true;
      }
      const int sig = service::stopSignalNumber();
      logLine(std::string("stop requested") + (sig ? " (signal " + std::to_string(sig) + ")" : "") +
              ": draining the frames in flight");
    }
    if (lcm) {
      handleCommands(*lcm, work, control);
      refused_log.update(*lcm, now);
    }
    const std::int64_t published = runner.published();
    if (published > last_published) {
      watchdog.progress(now);
      if (!ready_sent) {
        notifier.ready("tracking");
        ready_sent = true;
      }
      last_published = published;
    } else if (control.pause) {
      watchdog.idle(now);
    }
    // A stage working on one frame for longer than service.stall_timeout_s: no pings (systemd
    // restarts the service after WatchdogSec unless the stage recovers), and the stats on LCM
    // keep coming with the stalled stage even when no frame is published.
    const bool stage_stalled = stall_check.update(runner.health(), now, notifier);
    if (stage_stalled) work.publishStallStats();
    // After STOPPING=1 the service manager's stop timeout applies: no more pings (a notify
    // socket nobody reads any more must not block the drain).
    if (!stopping_sent && !stage_stalled && watchdog.shouldPing(now)) notifier.watchdog();
    if (progress_ns > 0 && now >= next_progress) {
      logLine("progress: " + std::to_string(published) + " poses, " +
              std::to_string(runner.captured()) + " frames captured");
      next_progress = now + progress_ns;
    }
  };
  const Status run_status = runner.run(slots, control, tick);
  if (!stopping_sent) notifier.stopping();
  logWarnings(work.takeWarnings());

  std::string error = run_status ? "" : run_status.message();
  // The files written at the end (on a full disk they fail after the first error, too).
  if (Status s = work.finish(); !s)
    error = error.empty() ? s.message() : error + "; then " + s.message();
  const run::StageTimes times = work.stageTimes();
  const rt::PipelineReport& rep = runner.report();
  run::RunSummary summary = work.summary();
  summary.source_frames_skipped = source->skippedFrames();
  summary.source_frames_skipped_detail = source->skippedFramesDetail();
  summary.source_counters = source->counters();
  std::tie(summary.altitude_readings, summary.altitude_rejected) = work.altitudeReadings();
  if (lcm) {
    refused_log.update(*lcm, rt::steadyNowNs(), true);
    summary.lcm_commands = lcm->commandCounts();
  }
  // The first error is the one reported; stats.json not written (a full disk) comes after it.
  if (Status s =
          run::writeFileAtomic(out_dir + "/" + run::files::kStats,
                               run::statsJson(cfg, source_spec, summary, work.outputs(), times, rep,
                                              error, work.mapJson(rep.after_publish_skipped),
                                              work.loopJson()));
      !s)
    error = error.empty() ? s.message() : error + "; then " + s.message();
  if (!error.empty()) return fail(Status::ioError(error));
  JsonObject j;
  j.add("source", source_spec)
      .add("mode", config::toString(cfg.mode))
      .add("out", out_dir)
      .add("threaded", !opts.sequential)
      .add("frames", work.summary().frames)
      .add("frames_tracked", work.summary().tracked)
      .add("source_frames_skipped", summary.source_frames_skipped)
      .add("frames_dropped", static_cast<std::int64_t>(rep.dropped))
      .add("stopped_by_signal", service::stopRequested())
      .add("fps", rep.fps, 2)
      .add("latency_p50_ms", rep.end_to_end.p50_ms, 3)
      .add("latency_p99_ms", rep.end_to_end.p99_ms, 3)
      .add("front_end_median_ms", times.median("front_end"), 3);
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace svslam::cli

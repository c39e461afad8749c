#include "pipeline/realtime/slam_stages.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "drivers/lcm/lcm_altitude.hpp"
#include "pipeline/realtime/stage_health.hpp"
#include "pipeline/service/scheduling.hpp"
#include "pipeline/thread_pool_executor.hpp"

namespace svslam::rt {

// Times the algorithm's sub-stages through the library's observer hook (one thread each).
class SlamStages::Clock final : public StageObserver {
 public:
  explicit Clock(run::StageTimes& times) : times_(times) {}
  void start() { last_ = steadyNowNs(); }
  void stageDone(const char* stage) override {
    const std::int64_t now = steadyNowNs();
    times_.add(stage, static_cast<double>(now - last_) * 1e-6);
    last_ = now;
  }

 private:
  run::StageTimes& times_;
  std::int64_t last_ = 0;
};

SlamStages::SlamStages(const config::RunConfig& cfg, drivers::StereoSource& source,
                       const std::string& out_dir, drivers::LcmLink* lcm)
    : cfg_(cfg), source_(source), out_dir_(out_dir), lcm_(lcm) {}

SlamStages::~SlamStages() {
  if (lcm_ && altitude_sub_ >= 0) (void)lcm_->unsubscribe(altitude_sub_);
}

std::pair<std::int64_t, std::int64_t> SlamStages::altitudeReadings() const {
  if (altitude_sub_ < 0) return {-1, -1};
  return {altitude_inbox_.accepted(), altitude_inbox_.rejected()};
}

Status SlamStages::buildEstimator() {
  estimator_ = makeEstimator(cfg_.mode, cfg_.slam, cfg_.odometry, source_.calibration());
  return estimator_->initStatus();
}

Status SlamStages::init() {
  stereo_stage_ = std::make_unique<StereoStage>(cfg_.odometry, source_.calibration());
  if (Status s = stereo_stage_->initStatus(); !s) return s;
  if (Status s = buildEstimator(); !s) return s;
  if (cfg_.mode == config::EstimatorMode::kMono &&
      cfg_.slam.mono_scale == MonoScaleSource::kAltitude) {
    if (!lcm_)
      return Status::invalidArgument(
          "slam.mono_scale altitude reads the altimeter on LCM (lcm.altitude_channel): enable "
          "LCM (lcm.enabled: true or --lcm-url)");
    auto sub = lcm_->subscribeRaw(cfg_.lcm.params.altitude_channel,
                                  [this](const std::uint8_t* data, std::size_t size) {
                                    drivers::AltitudeReading r;
                                    if (drivers::decodeAltitude(data, size, r))
                                      altitude_inbox_.push(r.t_ns, r.altitude_m);
                                    else
                                      altitude_inbox_.reject();
                                  });
    if (!sub) return sub.status();
    altitude_sub_ = *sub;
  }
  // One pool per stage thread (a ThreadPoolExecutor serves one parallelFor at a time); the
  // estimator's splits the EKF update's products. Results do not depend on either.
  if (cfg_.threads > 1) {
    stereo_executor_ = std::make_unique<ThreadPoolExecutor>(cfg_.threads);
    estimator_executor_ = std::make_unique<ThreadPoolExecutor>(cfg_.threads);
  } else {
    stereo_executor_ = std::make_unique<SerialExecutor>();
    estimator_executor_ = std::make_unique<SerialExecutor>();
  }
  stereo_clock_ = std::make_unique<Clock>(stereo_times_);
  estimator_clock_ = std::make_unique<Clock>(estimator_times_);
  publisher_ =
      std::make_unique<run::RunPublisher>(cfg_, out_dir_, estimator_->outputs(), lcm_, captured_);
  if (cfg_.map_enabled) {
    if (!cfg_.odometry.dense)
      return Status::invalidArgument(
          "map.enabled needs dense_stereo.enabled (the map is fused from dense stereo); set "
          "map.enabled: false to run without the map");
    map_stage_ = std::make_unique<MapStage>(cfg_, source_, out_dir_, lcm_);
    if (Status s = map_stage_->init(estimator_->outputs().pose_covariance); !s) return s;
  }
  if (cfg_.loop_enabled) {
    if (!cfg_.odometry.dense)
      return Status::invalidArgument(
          "loop.enabled needs dense_stereo.enabled (keyframe points take their depth from it)");
    loop_stage_ = std::make_unique<LoopStage>(cfg_, source_, out_dir_, lcm_);
    if (Status s = loop_stage_->init(); !s) return s;
  }
  Eigen::Isometry3d T;
  return publisher_->open(source_.groundTruth(0, T));
}

StageGraph SlamStages::graph(EdgePolicy capture_input) {
  feedback_.reset();
  last_stereo_seq_ = -1;
  StageGraph g;
  g.source = {"capture", [this](FrameSlot& s) { return capture(s); }};
  // Replayed as fast as possible (blocking edges: the mapper sees every frame) the estimator
  // waits for loop-closing solutions at fixed frames; a stage after it that fails ends the wait.
  if (loop_stage_) loop_stage_->setWaitForBackEnd(capture_input == EdgePolicy::kBlocking);
  g.stages = {{"stereo", [this](FrameSlot& s) { return stereo(s); }, capture_input},
              {"estimator", [this](FrameSlot& s) { return estimate(s); }},
              {"publisher", [this](FrameSlot& s) {
                 Status st = publisher_->publish(s);
                 if (!st && loop_stage_) loop_stage_->stopFeedback();
                 return st;
               }}};
  if (map_stage_ || loop_stage_) {
    StageSpec mapper{"mapper",
                     [this](FrameSlot& s) {
                       Status st = map_stage_ ? map_stage_->process(s) : Status::ok();
                       if (st && loop_stage_) st = loop_stage_->process(s);
                       if (st && map_stage_ && loop_stage_) st = replaceMapLive(s.frame.t_ns);
                       if (!st && loop_stage_) loop_stage_->stopFeedback();
                       return st;
                     },
                     capture_input};
    mapper.after_publish = true;
    g.stages.push_back(std::move(mapper));
  }
  g.on_thread_start = [this](const std::string& stage) { onThreadStart(stage); };
  g.prepare_slot = [this](FrameSlot& s) {
    const StereoCalibration& calib = source_.calibration();
    s.frame.left.resize(calib.width, calib.height);
    s.frame.right.resize(calib.width, calib.height);
    stereo_stage_->prepareOutput(s.stereo);
  };
  return g;
}

void SlamStages::onThreadStart(const std::string& stage) {
  service::setCurrentThreadName("svslam-" + stage);
  const config::PipelineConfig& p = cfg_.pipeline;
  const service::ThreadScheduling* sched = nullptr;
  if (stage == "capture") sched = &p.capture;
  if (stage == "stereo") sched = &p.stereo;
  if (stage == "estimator") sched = &p.estimator;
  if (stage == "publisher") sched = &p.publisher;
  if (stage == "mapper") {
    sched = &p.mapper;
    // The map is never worth a late pose: under normal scheduling the mapper thread yields the
    // cores to the pose path (nice +10 for this thread only; Linux nice is per thread). Not
    // SCHED_IDLE: on saturated cores that starves the mapper, and with it the save_map command.
    if (sched->fifo_priority == 0)
      (void)setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10);
  }
  if (!sched || (sched->cpus.empty() && sched->fifo_priority == 0)) return;
  std::string warning;
  const Status s = service::applyToCurrentThread(*sched, warning);
  std::lock_guard<std::mutex> lock(warn_mutex_);
  if (!s) warnings_ += stage + " thread: " + s.message() + "\n";
  if (!warning.empty()) warnings_ += stage + " thread: " + warning + "\n";
}

std::string SlamStages::takeWarnings() {
  std::string w = source_.takeWarnings();  // thread-safe by contract
  std::lock_guard<std::mutex> lock(warn_mutex_);
  w += warnings_;
  warnings_.clear();
  return w;
}

Result<bool> SlamStages::capture(FrameSlot& slot) {
  if (max_frames_ > 0 && captured_.load() >= max_frames_) return false;
  const std::int64_t t0 = steadyNowNs();
  auto more = source_.next(slot.frame);
  if (!more) return more.status();
  if (!*more) return false;
  capture_times_.add("load", static_cast<double>(steadyNowNs() - t0) * 1e-6);
  slot.has_ground_truth = source_.groundTruth(slot.frame.index, slot.T_gt_first_cam);
  ++captured_;
  return true;
}

Status SlamStages::stereo(FrameSlot& slot) {
  stereo_clock_->start();
  const auto left = slot.frame.left.cview(), right = slot.frame.right.cview();
  if (Status s =
          stereo_stage_->prepare(left, right, slot.stereo, *stereo_executor_, stereo_clock_.get());
      !s)
    return s;
  TrackingFeedback fb;  // no ROIs before the first frame
  if (stereo_stage_->needsFeedback() && last_stereo_seq_ >= 0) {
    const std::int64_t w0 = steadyNowNs();
    // Closed: the estimator failed (its error, written before the close, is the run's error).
    bool got = false;
    {
      StageWait waiting;  // on the estimator: not this stage's stall
      got = feedback_.wait(last_stereo_seq_, fb);
    }
    if (!got) return estimator_error_;
    stereo_times_.add("wait_estimator", static_cast<double>(steadyNowNs() - w0) * 1e-6);
    stereo_clock_->start();
  }
  last_stereo_seq_ = slot.seq;
  return stereo_stage_->finish(left, right, fb, slot.stereo, stereo_clock_.get());
}

Status SlamStages::replaceMapLive(TimeNs t_ns) {
  if (cfg_.map_replace_period_s <= 0) return Status::ok();
  const int solutions = loop_stage_->solutionsMade();
  const std::int64_t now = steadyNowNs();
  if (solutions == map_replaced_solutions_ || now < next_map_replace_ns_) return Status::ok();
  std::function<bool(std::int64_t, Eigen::Isometry3d&)> correction;
  if (!loop_stage_->liveFrameCorrections(correction)) return Status::ok();
  map_replaced_solutions_ = solutions;
  next_map_replace_ns_ = now + static_cast<std::int64_t>(cfg_.map_replace_period_s * 1e9);
  return map_stage_->replaceLive(correction, t_ns);
}

Status SlamStages::estimate(FrameSlot& slot) {
  const Status s = estimateFrame(slot);
  // The stereo stage of the next frame waits for this (a failed run: for nothing more).
  if (s) {
    feedback_.publish(slot.seq, estimator_->feedback());
  } else {
    estimator_error_ = s;
    feedback_.close();
  }
  return s;
}

Status SlamStages::estimateFrame(FrameSlot& slot) {
  const bool reset_hook = cfg_.pipeline.fault.reset_frame >= 0 &&
                          slot.frame.index == cfg_.pipeline.fault.reset_frame;
  if (reset_requested_.exchange(false) || reset_hook) {
    if (Status s = buildEstimator(); !s) return s;
    ++world_epoch_;  // a new world frame: the camera at the identity
  }
  slot.world_epoch = world_epoch_;
  Eigen::Isometry3d C_new_old, moved;
  Matrix6d cov_world;
  if (loop_stage_ &&
      loop_stage_->correctionBefore(slot.frame.index, world_epoch_, C_new_old, cov_world)) {
    if (Status s = estimator_->applyLoopCorrection(C_new_old, cov_world, moved); !s)
      return Status(s.code(), "frame " + std::to_string(slot.frame.index) + ": " + s.message());
    loop_stage_->correctionApplied(slot.frame.index, moved);
  }
  if (altitude_sub_ >= 0) {
    double altitude_m = 0;
    if (altitude_inbox_.latestAtOrBefore(slot.frame.t_ns, altitude_m))
      estimator_->setAltitude(altitude_m);
  }
  estimator_clock_->start();
  const Status s =
      estimator_->process(slot.frame.left.cview(), slot.frame.right.cview(), slot.stereo,
                          slot.result, *estimator_executor_, estimator_clock_.get());
  if (!s) return Status(s.code(), "frame " + std::to_string(slot.frame.index) + ": " + s.message());
  estimator_times_.add("front_end",
                       static_cast<double>(steadyNowNs() - slot.stamps.start_ns[0]) * 1e-6);
  if (lcm_ && estimator_->outputs().landmark_map) {
    const std::int64_t now = steadyNowNs();
    if (now >= next_map_ns_) {
      publishMapSummary(slot.frame.t_ns);
      next_map_ns_ = now + static_cast<std::int64_t>(cfg_.lcm.stats_period_s * 1e9);
    }
  }
  applySaveMap(slot.frame.t_ns);
  return Status::ok();
}

void SlamStages::requestSaveMap(const std::string& path, std::int64_t command_seq) {
  std::lock_guard<std::mutex> lock(save_mutex_);
  save_path_ = path;
  save_seq_ = command_seq;
}

void SlamStages::applySaveMap(TimeNs t_ns) {
  std::string save_path;
  std::int64_t save_seq = -1;
  {
    std::lock_guard<std::mutex> lock(save_mutex_);
    std::swap(save_seq, save_seq_);
    save_path = save_path_;
  }
  if (save_seq < 0) return;
  const std::string path = save_path.empty() ? out_dir_ + "/" + run::files::kLandmarks : save_path;
  const Status ws = writeMap(path);
  if (map_stage_) {  // the mapper writes its files and answers for both
    const std::size_t slash = path.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
    map_stage_->requestSave(dir, save_seq,
                            ws ? "map written to " + path + "; " : "error: " + ws.message() + "; ");
    return;
  }
  if (!lcm_) return;
  drivers::CommandStatus cs;
  cs.t_ns = t_ns;
  cs.seq = save_seq;
  cs.command = "save_map";
  cs.ok = ws.isOk();
  cs.message = ws ? "map written to " + path : ws.message();
  (void)lcm_->publishCommandStatus(cs);
}

Status SlamStages::writeMap(const std::string& path) {
  std::vector<run::PlyLandmark> ply;
  for (const MapLandmark& m : estimator_->map())
    ply.push_back(
        {m.id, m.p_world, m.cov.diagonal().cwiseMax(0.0).cwiseSqrt(), m.active, m.observations});
  return run::writeLandmarksPly(path, ply);
}

void SlamStages::publishMapSummary(TimeNs t_ns) {
  drivers::MapSummaryReport m;
  m.t_ns = t_ns;
  const std::vector<MapLandmark> map = estimator_->map();
  for (const MapLandmark& l : map) {
    if (!l.active) continue;
    m.points_world.push_back(l.p_world.cast<float>());
  }
  m.landmarks_in_state = static_cast<int>(m.points_world.size());
  m.landmarks_in_map = static_cast<int>(map.size());
  (void)lcm_->publishMap(m);
}

Status SlamStages::finish() {
  Status s = publisher_->close();
  if (estimator_ && estimator_->outputs().landmark_map) {
    const Status ws = writeMap(out_dir_ + "/" + run::files::kLandmarks);
    if (s) s = ws;
  }
  if (map_stage_) {
    const Status ms = map_stage_->finish();
    if (s) s = ms;
  }
  if (loop_stage_) {
    loop_stage_->stopFeedback();
    const Status ls = loop_stage_->finish(estimator_ && estimator_->outputs().landmark_map
                                              ? estimator_->map()
                                              : std::vector<MapLandmark>{});
    if (s) s = ls;
    if (map_stage_) {
      const Status rs = map_stage_->writeReplaced(
          [this](std::int64_t frame, Eigen::Isometry3d& M) {
            return loop_stage_->frameCorrection(frame, M);
          });
      if (s) s = rs;
    }
  }
  return s;
}

std::string SlamStages::mapJson(std::int64_t skipped_busy) const {
  return map_stage_ ? map_stage_->json(skipped_busy) : std::string();
}

std::string SlamStages::loopJson() const {
  return loop_stage_ ? loop_stage_->json() : std::string();
}

run::StageTimes SlamStages::stageTimes() const {
  run::StageTimes t = capture_times_;
  t.merge(stereo_times_);
  t.merge(estimator_times_);
  if (map_stage_) t.merge(map_stage_->times());
  if (loop_stage_) t.merge(loop_stage_->times());
  return t;
}

}  // namespace svslam::rt

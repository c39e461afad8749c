#include "pipeline/realtime/stage_work.hpp"

#include <chrono>
#include <cstdio>

#include "pipeline/service/scheduling.hpp"
#include "pipeline/thread_pool_executor.hpp"

namespace svslam::rt {

// Times the algorithm's sub-stages through the library's observer hook (one thread each).
class RunWork::Clock final : public StageObserver {
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

RunWork::RunWork(const config::RunConfig& cfg, drivers::StereoSource& source,
                 const std::string& out_dir, drivers::LcmLink* lcm)
    : cfg_(cfg),
      source_(source),
      out_dir_(out_dir),
      lcm_(lcm),
      ekf_mode_(cfg.mode == config::EstimatorMode::kEkf) {}

RunWork::~RunWork() = default;

Status RunWork::buildEstimator() {
  if (ekf_mode_) {
    slam_ = std::make_unique<SlamSystem>(cfg_.slam, cfg_.odometry, source_.calibration());
    return slam_->initStatus();
  }
  vo_ = std::make_unique<StereoOdometry>(cfg_.odometry, source_.calibration());
  return vo_->initStatus();
}

Status RunWork::init() {
  stereo_stage_ = std::make_unique<StereoStage>(cfg_.odometry, source_.calibration());
  if (Status s = stereo_stage_->initStatus(); !s) return s;
  if (Status s = buildEstimator(); !s) return s;
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
  if (Status s = traj_.open(out_dir_ + "/trajectory_kitti.txt", out_dir_ + "/trajectory_tum.txt");
      !s)
    return s;
  Eigen::Isometry3d T;
  if (source_.groundTruth(0, T)) {
    if (Status s = gt_.open(out_dir_ + "/groundtruth_kitti.txt", ""); !s) return s;
  }
  if (ekf_mode_) {
    if (Status s = cov_file_.open(out_dir_ + "/pose_covariance.txt"); !s) return s;
    cov_line_.reserve(36 * 32);  // 36 numbers of at most 31 characters each
  }
  return Status::ok();
}

void RunWork::onThreadStart(const char* stage) {
  const std::string name = std::string("svslam-") + stage;
  service::setCurrentThreadName(name);
  const config::PipelineConfig& p = cfg_.pipeline;
  const service::ThreadScheduling* sched = nullptr;
  const std::string st = stage;
  if (st == "capture") sched = &p.capture;
  if (st == "stereo") sched = &p.stereo;
  if (st == "estimator") sched = &p.estimator;
  if (st == "publisher") sched = &p.publisher;
  if (!sched || (sched->cpus.empty() && sched->fifo_priority == 0)) return;
  std::string warning;
  const Status s = service::applyToCurrentThread(*sched, warning);
  std::lock_guard<std::mutex> lock(warn_mutex_);
  if (!s) warnings_ += stage + std::string(" thread: ") + s.message() + "\n";
  if (!warning.empty()) warnings_ += stage + std::string(" thread: ") + warning + "\n";
}

std::string RunWork::takeWarnings() {
  std::lock_guard<std::mutex> lock(warn_mutex_);
  std::string w;
  w.swap(warnings_);
  return w;
}

Result<bool> RunWork::capture(FrameSlot& slot) {
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

Status RunWork::stereo(FrameSlot& slot) {
  stereo_clock_->start();
  return stereo_stage_->process(slot.frame.left.cview(), slot.frame.right.cview(), slot.stereo,
                                *stereo_executor_, stereo_clock_.get());
}

Status RunWork::estimate(FrameSlot& slot) {
  if (reset_requested_.exchange(false)) {
    if (Status s = buildEstimator(); !s) return s;
  }
  estimator_clock_->start();
  const auto left = slot.frame.left.cview();
  const auto right = slot.frame.right.cview();
  Status s;
  if (ekf_mode_) {
    s = slam_->process(left, right, slot.stereo, slot.result, *estimator_executor_,
                       estimator_clock_.get());
  } else {
    slot.result = SlamFrameResult{};
    s = vo_->frontEnd(left, right, slot.stereo, slot.result.odometry, *estimator_executor_,
                      estimator_clock_.get());
    if (s) s = vo_->estimateMotion(nullptr, slot.result.odometry, estimator_clock_.get());
    slot.result.T_world_cam = slot.result.odometry.T_first_cam;
  }
  if (!s) return Status(s.code(), "frame " + std::to_string(slot.frame.index) + ": " + s.message());
  estimator_times_.add("front_end",
                       static_cast<double>(steadyNowNs() - slot.stamps.stereo_start_ns) * 1e-6);
  if (lcm_ && ekf_mode_) {
    const std::int64_t now = steadyNowNs();
    if (now >= next_map_ns_) {
      publishMapSummary(slot.frame.t_ns);
      next_map_ns_ = now + static_cast<std::int64_t>(cfg_.lcm.stats_period_s * 1e9);
    }
  }
  std::string save_path;
  std::int64_t save_seq = -1;
  {
    std::lock_guard<std::mutex> lock(save_mutex_);
    std::swap(save_seq, save_seq_);
    save_path = save_path_;
  }
  if (save_seq >= 0) {
    const std::string path = save_path.empty() ? out_dir_ + "/landmarks.ply" : save_path;
    const Status ws = writeMap(path);
    if (lcm_) {
      drivers::CommandStatus cs;
      cs.t_ns = slot.frame.t_ns;
      cs.seq = save_seq;
      cs.command = "save_map";
      cs.ok = ws.isOk();
      cs.message = ws ? "map written to " + path : ws.message();
      (void)lcm_->publishCommandStatus(cs);
    }
  }
  return Status::ok();
}

void RunWork::requestSaveMap(const std::string& path, std::int64_t command_seq) {
  std::lock_guard<std::mutex> lock(save_mutex_);
  save_path_ = path;
  save_seq_ = command_seq;
}

Status RunWork::writeMap(const std::string& path) {
  std::vector<run::PlyLandmark> ply;
  if (slam_) {
    for (const MapLandmark& m : slam_->map())
      ply.push_back({m.id, m.p_world, m.cov.diagonal().cwiseMax(0.0).cwiseSqrt(), m.active,
                     m.observations});
  }
  return run::writeLandmarksPly(path, ply);
}

Status RunWork::publish(FrameSlot& slot) {
  const SlamFrameResult& sr = slot.result;
  if (Status s = traj_.append(slot.frame.t_ns, sr.T_world_cam); !s) return s;
  if (ekf_mode_) {
    cov_line_.clear();  // keeps its capacity (reserved in init)
    char num[32];
    for (int i = 0; i < 36; ++i) {
      std::snprintf(num, sizeof num, "%s%.9e", i ? " " : "", sr.pose_cov(i / 6, i % 6));
      cov_line_ += num;
    }
    if (Status s = cov_file_.append(cov_line_); !s) return s;
  }
  if (slot.has_ground_truth) {
    if (Status s = gt_.append(slot.frame.t_ns, slot.T_gt_first_cam); !s) return s;
  }
  summary_.add(slot.frame.index, sr, ekf_mode_);
  if (last_seq_ >= 0 && slot.seq > last_seq_ + 1) seq_gaps_ += slot.seq - last_seq_ - 1;
  last_seq_ = slot.seq;
  const std::int64_t now = steadyNowNs();
  e2e_.add(now - slot.stamps.capture_ns);
  stereo_ms_.add(slot.stamps.stereo_end_ns - slot.stamps.stereo_start_ns);
  estimate_ms_.add(slot.stamps.estimate_end_ns - slot.stamps.estimate_start_ns);
  if (lcm_) {
    drivers::PoseReport p;
    p.t_ns = slot.frame.t_ns;
    p.publish_t_ns = slot.frame.t_ns + (now - slot.stamps.capture_ns);  // source clock
    p.seq = slot.seq;
    p.T_world_cam = sr.T_world_cam;
    p.cov = ekf_mode_ ? sr.pose_cov : sr.odometry.covariance;
    p.status = sr.odometry.frame == 0 ? drivers::TrackingStatus::kInitializing
               : sr.odometry.tracked  ? drivers::TrackingStatus::kTracking
                                      : drivers::TrackingStatus::kLost;
    // A pose that cannot be published (non-finite) is an error of this frame, not of the run:
    // it is skipped on LCM (the files keep the line) and counted by the link.
    (void)lcm_->publishPose(p);
    if (now >= next_stats_ns_) {
      publishStats(slot.frame.t_ns);
      next_stats_ns_ = now + static_cast<std::int64_t>(cfg_.lcm.stats_period_s * 1e9);
    }
  }
  return Status::ok();
}

void RunWork::publishStats(TimeNs t_ns) {
  drivers::StatsReport r;
  r.t_ns = t_ns;
  r.frames_in = captured_;
  r.frames_out = summary_.frames;
  r.frames_dropped = seq_gaps_;
  r.frames_tracked = summary_.tracked;
  const LatencySummary st = stereo_ms_.summary(), es = estimate_ms_.summary(), e2e = e2e_.summary();
  r.stages.push_back({"stereo", st.p50_ms, st.p99_ms, st.max_ms});
  r.stages.push_back({"estimator", es.p50_ms, es.p99_ms, es.max_ms});
  r.e2e_p50_ms = e2e.p50_ms;
  r.e2e_p99_ms = e2e.p99_ms;
  r.e2e_max_ms = e2e.max_ms;
  (void)lcm_->publishStats(r);
}

void RunWork::publishMapSummary(TimeNs t_ns) {
  drivers::MapSummaryReport m;
  m.t_ns = t_ns;
  const std::vector<MapLandmark> map = slam_->map();
  for (const MapLandmark& l : map) {
    if (!l.active) continue;
    m.points_world.push_back(l.p_world.cast<float>());
  }
  m.landmarks_in_state = static_cast<int>(m.points_world.size());
  m.landmarks_in_map = static_cast<int>(map.size());
  (void)lcm_->publishMap(m);
}

Status RunWork::finish() {
  traj_.close();
  gt_.close();
  cov_file_.close();
  if (ekf_mode_ && slam_) return writeMap(out_dir_ + "/landmarks.ply");
  return Status::ok();
}

run::StageTimes RunWork::stageTimes() const {
  run::StageTimes t = capture_times_;
  t.merge(stereo_times_);
  t.merge(estimator_times_);
  return t;
}

}  // namespace svslam::rt

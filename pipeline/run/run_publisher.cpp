#include "pipeline/run/run_publisher.hpp"

#include <cstdio>

#include "slam/pose_jacobians.hpp"

namespace svslam::run {

RunPublisher::RunPublisher(const config::RunConfig& cfg, const std::string& out_dir,
                           EstimatorOutputs outputs, drivers::LcmLink* lcm,
                           const std::atomic<std::int64_t>& captured)
    : cfg_(cfg), out_dir_(out_dir), outputs_(outputs), lcm_(lcm), captured_(captured) {}

Status RunPublisher::open(bool ground_truth) {
  if (Status s = traj_.open(out_dir_ + "/" + files::kTrajectoryKitti,
                            out_dir_ + "/" + files::kTrajectoryTum);
      !s)
    return s;
  if (ground_truth) {
    if (Status s = gt_.open(out_dir_ + "/" + files::kGroundTruthKitti, ""); !s) return s;
  }
  if (outputs_.pose_covariance) {
    if (Status s = cov_file_.open(out_dir_ + "/" + files::kPoseCovariance); !s) return s;
    cov_line_.reserve(36 * 32);  // 36 numbers of at most 31 characters each
  }
  if (cfg_.pipeline.latency_log) {
    if (Status s = latency_file_.open(out_dir_ + "/" + files::kLatency); !s) return s;
    latency_line_.reserve(64);
  }
  return Status::ok();
}

Status RunPublisher::close() {
  Status first;
  for (const Status& s : {traj_.close(), gt_.close(), cov_file_.close(), latency_file_.close()})
    if (first && !s) first = s;
  return first;
}

Status RunPublisher::publish(const rt::FrameSlot& slot) {
  const SlamFrameResult& sr = slot.result;
  if (Status s = traj_.append(slot.frame.t_ns, sr.T_world_cam); !s) return s;
  if (outputs_.pose_covariance) {
    cov_line_.clear();  // keeps its capacity (reserved in open)
    char num[32];
    for (int i = 0; i < 36; ++i) {
      std::snprintf(num, sizeof num, "%s%.9e", i ? " " : "",
                    sr.pose_cov(i / 6, i % 6) + sr.pose_cov_consider(i / 6, i % 6));
      cov_line_ += num;
    }
    if (Status s = cov_file_.append(cov_line_); !s) return s;
  }
  if (slot.has_ground_truth) {
    if (Status s = gt_.append(slot.frame.t_ns, slot.T_gt_first_cam); !s) return s;
  }
  summary_.add(slot.frame.index, sr);
  if (last_seq_ >= 0 && slot.seq > last_seq_ + 1) seq_gaps_ += slot.seq - last_seq_ - 1;
  last_seq_ = slot.seq;
  const std::int64_t now = rt::steadyNowNs();
  if (cfg_.pipeline.latency_log) {
    char line[64];
    std::snprintf(line, sizeof line, "%lld %.3f", static_cast<long long>(slot.seq),
                  static_cast<double>(now - slot.stamps.capture_ns) * 1e-6);
    latency_line_.assign(line);
    if (Status s = latency_file_.append(latency_line_); !s) return s;
  }
  if (!lcm_) return Status::ok();
  drivers::PoseReport p;
  p.t_ns = slot.frame.t_ns;
  p.publish_t_ns = slot.frame.t_ns + (now - slot.stamps.capture_ns);  // source clock
  p.seq = slot.seq;
  p.T_world_cam = sr.T_world_cam;
  // pose_t's convention: the right-multiplied error in the camera frame (lcm/pose_t.lcm).
  p.cov = cameraFrameCovariance(sr.T_world_cam, sr.pose_cov + sr.pose_cov_consider);
  p.status = sr.initializing          ? drivers::TrackingStatus::kInitializing
             : sr.mono                ? drivers::TrackingStatus::kMonocular
             : sr.odometry.frame == 0 ? drivers::TrackingStatus::kInitializing
             : sr.relocalised         ? drivers::TrackingStatus::kTracking
             : sr.lost                ? drivers::TrackingStatus::kLost
             : sr.odometry.tracked    ? drivers::TrackingStatus::kTracking
                                      : drivers::TrackingStatus::kLost;
  p.motion_inliers = sr.odometry.inliers;
  p.motion_residual_per_dof =
      sr.odometry.inliers > 0
          ? sr.odometry.motion_rms_mahalanobis * sr.odometry.motion_rms_mahalanobis / 3.0
          : 0.0;
  // Stereo observations have 3 dof, bearings 2.
  const int obs_dof = 3 * sr.nis_count + 2 * sr.bearing_count;
  p.observation_nis_per_dof = obs_dof > 0 ? (sr.nis_sum + sr.bearing_nis_sum) / obs_dof : 0.0;
  p.landmarks_observed = sr.nis_count + sr.bearing_count;
  p.search = sr.odometry.retried       ? drivers::SearchKind::kRetried
             : sr.odometry.repredicted ? drivers::SearchKind::kRepredicted
                                       : drivers::SearchKind::kPredicted;
  // A pose that cannot be published (non-finite) is an error of this frame, not of the run:
  // it is skipped on LCM (the files keep the line) and counted by the link.
  (void)lcm_->publishPose(p);
  if (now >= next_stats_ns_) {
    publishStats(slot.frame.t_ns);
    next_stats_ns_ = now + static_cast<std::int64_t>(cfg_.lcm.stats_period_s * 1e9);
  }
  return Status::ok();
}

void RunPublisher::publishStats(TimeNs t_ns) {
  drivers::StatsReport r;
  r.t_ns = t_ns;
  r.frames_in = captured_.load();
  r.frames_out = summary_.frames;
  r.frames_dropped = seq_gaps_;
  r.frames_tracked = summary_.tracked;
  if (timings_) {  // the frames before this one (the runner records a frame once published)
    for (std::size_t i = 1; i < timings_->names().size(); ++i) {
      if (timings_->names()[i] == "publisher") continue;
      const rt::LatencySummary l = timings_->stage(i).summary();
      r.stages.push_back({timings_->names()[i], l.p50_ms, l.p99_ms, l.max_ms});
    }
    const rt::LatencySummary e2e = timings_->endToEnd().summary();
    r.e2e_p50_ms = e2e.p50_ms;
    r.e2e_p99_ms = e2e.p99_ms;
    r.e2e_max_ms = e2e.max_ms;
  }
  r.commands = lcm_->commandCounts();
  const std::int64_t now = rt::steadyNowNs();
  addHealth(r, now);
  (void)lcm_->publishStats(r);
  std::lock_guard<std::mutex> lock(stats_mu_);
  last_stats_ = std::move(r);
  last_stats_ns_ = now;
}

void RunPublisher::addHealth(drivers::StatsReport& r, std::int64_t now_ns) const {
  r.stalled_stage.clear();
  r.stalled_ms = 0;
  r.stalls.clear();
  if (!health_) return;
  const rt::HealthSnapshot h = health_->snapshot(now_ns);
  r.stalled_stage = h.stalled_stage;
  r.stalled_ms = h.stalled_ms;
  for (const rt::StageStall& s : h.stalls) r.stalls.push_back({s.stage, s.count, s.longest_ms});
}

void RunPublisher::publishStallStats() {
  if (!lcm_) return;
  const std::int64_t now = rt::steadyNowNs();
  const std::int64_t period_ns = static_cast<std::int64_t>(cfg_.lcm.stats_period_s * 1e9);
  std::lock_guard<std::mutex> lock(stats_mu_);
  const std::int64_t last = last_stats_ns_.load();
  if (last != 0 && now - last < period_ns) return;
  drivers::StatsReport r = last_stats_;
  if (last != 0) r.t_ns += now - last;
  r.frames_in = captured_.load();
  r.commands = lcm_->commandCounts();
  addHealth(r, now);
  (void)lcm_->publishStats(r);
  last_stats_ = std::move(r);
  last_stats_ns_ = now;
}

}  // namespace svslam::run

#pragma once
// The publisher stage of `svslam run`: per frame, the trajectory lines (trajectory_kitti.txt,
// trajectory_tum.txt), the pose covariance line (pose_covariance.txt, when the estimator has a
// pose covariance), the ground truth line (groundtruth_kitti.txt, when the source knows it), the
// run summary, the latency line (latency.txt, with pipeline.latency_log: "seq ms", the frame's
// capture sequence number and its capture-to-publish latency), and on LCM the pose with its
// covariance and, every lcm.stats_period_s, the stats.
// Runs on one thread; every buffer is reused from frame to frame.
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "core/status.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/frame_slot.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/run/run_outputs.hpp"
#include "pipeline/run/run_summary.hpp"
#include "slam/estimator.hpp"

namespace svslam::run {

class RunPublisher {
 public:
  // `lcm` (may be null) and `captured` (frames read so far) outlive this object.
  RunPublisher(const config::RunConfig& cfg, const std::string& out_dir, EstimatorOutputs outputs,
               drivers::LcmLink* lcm, const std::atomic<std::int64_t>& captured);
  // Opens the files; `ground_truth`: the source knows the true poses.
  Status open(bool ground_truth);
  Status publish(const rt::FrameSlot& slot);
  // The runner's latencies for the stats on LCM (null: none sent).
  void setTimings(const rt::StageTimings* timings) { timings_ = timings; }
  // The runner's stage health for the stalls in the stats (null: none reported).
  void setHealth(const rt::StageHealth* health) { health_ = health; }
  // Any thread (the control loop, while a stage is stalled): when no stats went out for
  // lcm.stats_period_s, sends the last ones again with the frame count and the stalls of now
  // (t_ns moved on by the time since). Nothing without LCM.
  void publishStallStats();
  // Closes the files; error naming the first file whose close failed.
  Status close();
  const RunSummary& summary() const { return summary_; }

 private:
  void publishStats(TimeNs t_ns);
  void addHealth(drivers::StatsReport& r, std::int64_t now_ns) const;

  const config::RunConfig& cfg_;
  std::string out_dir_;
  EstimatorOutputs outputs_;
  drivers::LcmLink* lcm_;
  const std::atomic<std::int64_t>& captured_;
  const rt::StageTimings* timings_ = nullptr;
  const rt::StageHealth* health_ = nullptr;
  // The last stats sent and when (steady clock), for publishStallStats.
  std::mutex stats_mu_;
  drivers::StatsReport last_stats_;
  std::atomic<std::int64_t> last_stats_ns_{0};
  TrajectoryWriter traj_, gt_;
  LineWriter cov_file_, latency_file_;
  std::string cov_line_;      // one pose_covariance.txt line, reused
  std::string latency_line_;  // one latency.txt line, reused
  RunSummary summary_;
  std::int64_t last_seq_ = -1, seq_gaps_ = 0, next_stats_ns_ = 0;
};

}  // namespace svslam::run

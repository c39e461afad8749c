#pragma once
// The work of `svslam run` cut into the pipeline's stages (realtime/pipeline_runner.hpp):
//   capture    the next pair of the source (and its ground truth, when known);
//   stereo     StereoStage: dense stereo, interest points, stereo matching;
//   estimator  temporal matching, VME and, in ekf mode, the EKF (SlamSystem); commands that
//              touch the map (reset, save_map) are applied here, between two frames;
//   publisher  the output files (trajectory_kitti/tum, pose_covariance, groundtruth), the pose
//              on LCM, and every stats_period_s the stats and map summary on LCM.
#include <atomic>
#include <memory>
#include <mutex>
#include <string>

#include "core/executor.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "drivers/source/stereo_source.hpp"
#include "odometry/stereo_odometry.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/run/run_outputs.hpp"
#include "pipeline/run/run_summary.hpp"
#include "slam/slam_system.hpp"

namespace svslam::rt {

class RunWork final : public PipelineWork {
 public:
  // `source` and `lcm` (may be null) outlive the work. Outputs go to `out_dir`.
  RunWork(const config::RunConfig& cfg, drivers::StereoSource& source, const std::string& out_dir,
          drivers::LcmLink* lcm);
  ~RunWork() override;
  // Opens the output files and builds the estimator; error naming what failed.
  Status init();

  Result<bool> capture(FrameSlot& slot) override;
  Status stereo(FrameSlot& slot) override;
  Status estimate(FrameSlot& slot) override;
  Status publish(FrameSlot& slot) override;
  void onThreadStart(const char* stage) override;

  // Capture ends after `n` frames (0 = the whole source).
  void setMaxFrames(int n) { max_frames_ = n; }
  // Commands (any thread): applied by the estimator before its next frame.
  void requestReset() { reset_requested_ = true; }
  // Writes the map (landmarks.ply) to `path` (empty: <out>/landmarks.ply) after the next frame.
  void requestSaveMap(const std::string& path, std::int64_t command_seq);

  // After the run (stages stopped): closes the files, writes landmarks.ply.
  Status finish();
  const run::RunSummary& summary() const { return summary_; }
  // Algorithm stage times (dense_stereo, detect, stereo_match, temporal_match, motion, ekf,
  // front_end = stereo + estimator work, load). Read after the run.
  run::StageTimes stageTimes() const;
  // Warnings met while starting threads (scheduling not permitted), for the log.
  std::string takeWarnings();

 private:
  class Clock;
  Status buildEstimator();
  Status writeMap(const std::string& path);
  void publishStats(TimeNs t_ns);
  void publishMapSummary(TimeNs t_ns);

  config::RunConfig cfg_;
  drivers::StereoSource& source_;
  std::string out_dir_;
  drivers::LcmLink* lcm_;
  bool ekf_mode_;
  std::atomic<std::int64_t> captured_{0};
  int max_frames_ = 0;
  // Stereo thread.
  std::unique_ptr<StereoStage> stereo_stage_;
  std::unique_ptr<Executor> stereo_executor_;
  std::unique_ptr<Clock> stereo_clock_;
  run::StageTimes stereo_times_;
  // Estimator thread.
  std::unique_ptr<SlamSystem> slam_;
  std::unique_ptr<StereoOdometry> vo_;
  std::unique_ptr<Executor> estimator_executor_;  // its own pool: runs beside the stereo one
  std::unique_ptr<Clock> estimator_clock_;
  run::StageTimes estimator_times_;
  std::atomic<bool> reset_requested_{false};
  std::int64_t next_map_ns_ = 0;
  std::mutex save_mutex_;
  std::string save_path_;
  std::int64_t save_seq_ = -1;  // pending save_map command (-1: none)
  // Capture thread.
  run::StageTimes capture_times_;
  // Publisher thread.
  run::TrajectoryWriter traj_, gt_;
  run::LineWriter cov_file_;
  std::string cov_line_;  // one pose_covariance.txt line, reused
  run::RunSummary summary_;
  LatencyRecorder e2e_, stereo_ms_, estimate_ms_;
  std::int64_t last_seq_ = -1, seq_gaps_ = 0, next_stats_ns_ = 0;
  std::mutex warn_mutex_;
  std::string warnings_;
};

}  // namespace svslam::rt

#pragma once
// The stages of `svslam run`, as the stage graph the runner executes
// (realtime/stage_graph.hpp):
//   capture    the next pair of the source (and its ground truth, when known);
//   stereo     the StereoStage: dense stereo, interest points, ROIs, stereo matching, 3D points.
//              With ROI tracking its second half waits for the estimator's feedback on the
//              previous frame (a FeedbackCell: the only edge running backwards);
//   estimator  the Estimator of the configured mode (vo or ekf), one call per frame; commands
//              that touch the map (reset, save_map) are applied here, between two frames;
//   publisher  the run's outputs (run/run_publisher.hpp): files, the pose and stats on LCM;
//   mapper     (map.enabled or loop.enabled) after publication: the elevation map
//              (realtime/map_stage.hpp), then loop closing's keyframes (realtime/loop_stage.hpp,
//              whose back end has a thread of its own).
// Each stage is owned once, here; the runner owns the threads, edges and timing.
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "core/executor.hpp"
#include "drivers/lcm/lcm_transport.hpp"
#include "drivers/source/stereo_source.hpp"
#include "odometry/stereo_stage.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/realtime/altitude_inbox.hpp"
#include "pipeline/realtime/edges.hpp"
#include "pipeline/realtime/loop_stage.hpp"
#include "pipeline/realtime/map_stage.hpp"
#include "pipeline/realtime/pipeline_runner.hpp"
#include "pipeline/run/run_outputs.hpp"
#include "pipeline/run/run_publisher.hpp"
#include "pipeline/run/run_summary.hpp"
#include "slam/estimator.hpp"

namespace svslam::rt {

class SlamStages {
 public:
  // `source` and `lcm` (may be null) outlive this object. Outputs go to `out_dir`.
  SlamStages(const config::RunConfig& cfg, drivers::StereoSource& source,
             const std::string& out_dir, drivers::LcmLink* lcm);
  ~SlamStages();
  // Builds the stages and opens the output files; error naming what failed.
  Status init();
  // The stage list; `capture_input` is the policy of the edge capture -> stereo.
  StageGraph graph(EdgePolicy capture_input);
  // The runner's latencies, for the stats on LCM (read by the publisher on its thread).
  void setTimings(const StageTimings* timings) { publisher_->setTimings(timings); }
  // The runner's stage health, for the stalls in the stats on LCM.
  void setHealth(const StageHealth* health) { publisher_->setHealth(health); }
  // Control loop, while a stage is stalled: the stats on LCM even though no frame is published
  // (run/run_publisher.hpp).
  void publishStallStats() { publisher_->publishStallStats(); }

  // Capture ends after `n` frames (0 = the whole source).
  void setMaxFrames(int n) { max_frames_ = n; }
  // Commands (any thread): applied by the estimator before its next frame.
  void requestReset() { reset_requested_ = true; }
  // Writes the map (landmarks.ply) to `path` (empty: <out>/landmarks.ply) after the next frame,
  // and the elevation map files into the folder of `path` (mapper thread, after its next frame).
  void requestSaveMap(const std::string& path, std::int64_t command_seq);

  // After the run (stages stopped): closes the files, writes landmarks.ply.
  Status finish();
  const run::RunSummary& summary() const { return publisher_->summary(); }
  // What the estimator produces beyond the pose (after init()).
  EstimatorOutputs outputs() const { return estimator_->outputs(); }
  // Algorithm stage times (dense_stereo, detect, stereo_match, temporal_match, motion, ekf,
  // front_end = stereo + estimator work, load). Read after the run.
  run::StageTimes stageTimes() const;
  // stats.json's "map" object (empty without the mapper); `skipped_busy` from the runner.
  std::string mapJson(std::int64_t skipped_busy) const;
  // The mapper (null when map.enabled is false); its map is the mapper thread's.
  const MapStage* mapStage() const { return map_stage_.get(); }
  // stats.json's "loop" object (empty without loop closing).
  std::string loopJson() const;
  // Altimeter readings received and rejected (-1, -1 when the run does not read them).
  std::pair<std::int64_t, std::int64_t> altitudeReadings() const;
  // Warnings met while starting threads (scheduling not permitted) and the source's (a camera
  // reconnected or frozen), for the log.
  std::string takeWarnings();

 private:
  class Clock;
  Result<bool> capture(FrameSlot& slot);
  Status stereo(FrameSlot& slot);
  Status estimate(FrameSlot& slot);
  Status estimateFrame(FrameSlot& slot);
  void onThreadStart(const std::string& stage);
  Status buildEstimator();
  Status writeMap(const std::string& path);
  void applySaveMap(TimeNs t_ns);
  void publishMapSummary(TimeNs t_ns);

  config::RunConfig cfg_;
  drivers::StereoSource& source_;
  // The altimeter (mode mono, slam.mono_scale altitude): filled by the LCM handler, read by the
  // estimator before each frame; altitude_sub_ the subscription (-1: none).
  AltitudeInbox altitude_inbox_;
  int altitude_sub_ = -1;
  std::string out_dir_;
  drivers::LcmLink* lcm_;
  std::atomic<std::int64_t> captured_{0};
  int max_frames_ = 0;
  // Capture thread.
  run::StageTimes capture_times_;
  // Stereo thread.
  std::unique_ptr<StereoStage> stereo_stage_;
  std::unique_ptr<Executor> stereo_executor_;
  std::unique_ptr<Clock> stereo_clock_;
  run::StageTimes stereo_times_;
  std::int64_t last_stereo_seq_ = -1;  // the frame the stereo stage handed on last
  // Estimator -> stereo: the feedback on each frame (ROI tracking).
  FeedbackCell<TrackingFeedback> feedback_;
  Status estimator_error_;  // written before feedback_ is closed, read after
  // Estimator thread.
  std::unique_ptr<Estimator> estimator_;
  std::unique_ptr<Executor> estimator_executor_;  // its own pool: runs beside the stereo one
  std::unique_ptr<Clock> estimator_clock_;
  run::StageTimes estimator_times_;
  std::atomic<bool> reset_requested_{false};
  int world_epoch_ = 0;  // estimator thread: resets so far (FrameSlot::world_epoch)
  // Mapper thread: the map re-placed during the run after a new loop-closing solution, at most
  // every map.replace_period_s (MapStage::replaceLive).
  Status replaceMapLive(TimeNs t_ns);
  int map_replaced_solutions_ = 0;
  std::int64_t next_map_replace_ns_ = 0;
  std::int64_t next_map_ns_ = 0;
  std::mutex save_mutex_;
  std::string save_path_;
  std::int64_t save_seq_ = -1;  // pending save_map command (-1: none)
  // Publisher thread.
  std::unique_ptr<run::RunPublisher> publisher_;
  // Mapper thread (null when map.enabled is false).
  std::unique_ptr<MapStage> map_stage_;
  std::unique_ptr<LoopStage> loop_stage_;
  std::mutex warn_mutex_;
  std::string warnings_;
};

}  // namespace svslam::rt
